#include "output/exr_parts.hpp"

#include <algorithm>
#include <stdexcept>
#include <thread>

#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfThreading.h>

#include "output/fresh_file.hpp"

namespace shadow::output {

void use_every_core() {
  static const bool once = [] {
    Imf::setGlobalThreadCount(int(std::max(1u, std::thread::hardware_concurrency())));
    return true;
  }();
  (void)once;
}

void write_exr_parts(const std::filesystem::path& file, const std::vector<ExrPart>& parts) {
  if (parts.empty()) throw std::runtime_error(file.string() + ": no parts to write");
  use_every_core();
  remove_old_file(file);
  try {
    const auto rows = [](const Imf::Header& h) {
      return h.dataWindow().max.y - h.dataWindow().min.y + 1;
    };
    if (parts.size() == 1) {
      Imf::OutputFile out(file.c_str(), parts[0].header);
      out.setFrameBuffer(parts[0].pixels);
      out.writePixels(rows(parts[0].header));
      return;
    }
    std::vector<Imf::Header> headers;
    for (const ExrPart& p : parts) headers.push_back(p.header);
    Imf::MultiPartOutputFile out(file.c_str(), headers.data(), int(headers.size()));
    for (size_t i = 0; i < parts.size(); ++i) {
      Imf::OutputPart part(out, int(i));
      part.setFrameBuffer(parts[i].pixels);
      part.writePixels(rows(parts[i].header));
    }
  } catch (const std::exception& e) {  // Iex's errors name the cause (a full disk, a bad path)
    throw std::runtime_error(file.string() + ": " + e.what());
  }
}

}  // namespace shadow::output
