#include "output/stream_writer.hpp"

#include <chrono>
#include <stdexcept>
#include <system_error>

#include <OpenEXR/ImfOutputFile.h>

#include "output/exr_parts.hpp"
#include "output/fresh_file.hpp"

namespace shadow::output {

struct StreamWriter::File {
  size_t index = 0;  // into the textures
  const float* data = nullptr;
  uint64_t row_bytes = 0;
  uint32_t height = 0;
  uint32_t rows_written = 0;
  std::filesystem::path path;
  std::unique_ptr<Imf::OutputFile> out;

  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(path.string() + ": " + why);
  }
};

StreamWriter::StreamWriter(std::filesystem::path dir, OutputOptions options)
    : dir_(std::move(dir)), options_(std::move(options)) {}

StreamWriter::~StreamWriter() {
  discard();
}

void StreamWriter::discard() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  files_.clear();
  streamed_.clear();
  arrived_.clear();
  stop_ = false;
  error_ = nullptr;
  streamed_ms_ = 0;
}

void StreamWriter::start(const std::vector<Texture>& textures) {
  discard();
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw std::runtime_error(dir_.string() + ": cannot create directory: " + ec.message());
  streamed_.assign(textures.size(), false);
  arrived_.assign(textures.size(), 0);
  use_every_core();  // before the files open: each takes the pool it finds
  for (size_t i = 0; i < textures.size(); ++i) {
    const Texture& t = textures[i];
    if (!is_plain(t) || t.width == 0 || t.height == 0 || t.channels == 0 || t.faces != 1) continue;
    auto f = std::make_unique<File>();
    f->index = i;
    f->data = t.data.data();
    f->row_bytes = uint64_t{t.width} * t.channels * sizeof(float);
    f->height = t.height;
    f->path = exr_path(t, dir_);
    try {
      const ExrPart part = exr_part(t, options_.exr_compression, f->data);
      remove_old_file(f->path);
      f->out = std::make_unique<Imf::OutputFile>(f->path.c_str(), part.header);
      f->out->setFrameBuffer(part.pixels);
    } catch (const std::exception& e) {  // Iex's errors name the cause
      f->fail(e.what());
    }
    streamed_[i] = true;
    files_.push_back(std::move(f));
  }
  if (!files_.empty()) thread_ = std::thread([this] { run(); });
}

void StreamWriter::arrived(size_t index, uint64_t bytes) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error_) std::rethrow_exception(error_);
    if (index >= arrived_.size() || !streamed_[index]) return;
    arrived_[index] = bytes;
  }
  wake_.notify_one();
}

// Writes each file's rows as they arrive, files in stream order, and closes each when done.
void StreamWriter::run() {
  const auto start = std::chrono::steady_clock::now();
  try {
    for (const std::unique_ptr<File>& f : files_) {
      while (f->rows_written < f->height) {
        uint32_t ready = 0;
        {
          std::unique_lock<std::mutex> lock(mutex_);
          wake_.wait(lock,
                     [&] { return stop_ || arrived_[f->index] / f->row_bytes > f->rows_written; });
          if (stop_) return;
          ready = uint32_t(arrived_[f->index] / f->row_bytes);
        }
        try {
          f->out->writePixels(int(ready - f->rows_written));  // the next rows, in order
        } catch (const std::exception& e) {
          f->fail(e.what());
        }
        f->rows_written = ready;
      }
      f->out.reset();  // closes the file
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = std::current_exception();
  }
  streamed_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::vector<WrittenFile> StreamWriter::finish(const std::vector<Texture>& textures) {
  if (thread_.joinable()) thread_.join();  // every row has arrived: the thread ends by itself
  if (error_) std::rethrow_exception(error_);
  return write_products(textures, dir_, options_, streamed_);
}

}  // namespace shadow::output
