// Writes a Render reply's plain textures (write_products.hpp's is_plain) as EXR files while the
// reply still arrives: each texture's file is opened when the header comes and its rows are
// written, on a thread of its own, as soon as their bytes are in. So file writing overlaps the
// wire instead of following it. The rest (mip chains, cubes, SATs) and the PNG previews, which
// need whole textures, are written by finish().
#pragma once

#include <condition_variable>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "output/output_options.hpp"
#include "output/write_products.hpp"
#include "wire/types.hpp"

namespace shadow::output {

class StreamWriter {
 public:
  StreamWriter(std::filesystem::path dir, OutputOptions options);
  ~StreamWriter();  // stops the thread; files left open are closed as they are
  StreamWriter(const StreamWriter&) = delete;
  StreamWriter& operator=(const StreamWriter&) = delete;

  // `textures` as the header described them, at full size; their storage must stay where it is
  // until finish() or discard() (ResultAssembler::partial() keeps it there). Creates the
  // directory, opens the files and starts writing. A second start() discards the first.
  void start(const std::vector<Texture>& textures);
  // Stops writing and closes the files as they are, so the textures' storage may go (the
  // stream broke off); start() may follow for a new stream.
  void discard();
  // The first `bytes` of texture `index` are final. Rethrows the thread's error, if any.
  void arrived(size_t index, uint64_t bytes);
  // After the whole reply: waits for the rows, closes the files, writes everything else.
  // `textures` are the same textures (finish()ed, same storage). Throws std::runtime_error
  // naming the file that failed.
  std::vector<WrittenFile> finish(const std::vector<Texture>& textures);

  // Milliseconds from start() until the last streamed row was written (0 when none were).
  double streamed_ms() const { return streamed_ms_; }

 private:
  struct File;
  void run();

  std::filesystem::path dir_;
  OutputOptions options_;
  std::vector<std::unique_ptr<File>> files_;  // one per plain texture, in stream order
  std::vector<bool> streamed_;                // by texture index

  std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<uint64_t> arrived_;  // bytes, by texture index
  bool stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;
  double streamed_ms_ = 0;
};

}  // namespace shadow::output
