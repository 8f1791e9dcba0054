// How shadowctl writes products: the EXR compression and which PNG previews are written.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace shadow::output {

// OpenEXR's lossless compressions, by their usual names (OpenImageIO's `compression`). The
// lossy ones (pxr24, b44, dwaa, dwab) would change float32 values and are not offered.
inline constexpr std::array<std::string_view, 5> kExrCompressions = {"none", "rle", "zips", "zip",
                                                                     "piz"};
// Measured on shadow maps and visibility (docs/benchmarks.md, "End to end"): about as fast to
// write as no compression (zip/zips/piz take 4-9x as long), with files 20-40% smaller on shadow
// maps and ~65% smaller on visibility.
inline constexpr std::string_view kDefaultExrCompression = "rle";

// PNG previews: none; at most kPreviewEdge pixels along the longer side (every k-th texel: a
// preview is for looking at, and a 4096² map's full one costs more than the rest of its files,
// docs/benchmarks.md); or one pixel per texel.
enum class Preview { kNone, kPng, kFull };
inline constexpr uint32_t kPreviewEdge = 1024;

struct OutputOptions {
  std::string exr_compression{kDefaultExrCompression};  // one of kExrCompressions
  Preview preview = Preview::kPng;
};

// True when `name` is in kExrCompressions.
bool known_exr_compression(std::string_view name);

}  // namespace shadow::output
