// How shadowctl writes products: the EXR compression and which PNG previews are written.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "wire/types.hpp"

namespace shadow::output {

// OpenEXR's lossless compressions, by their usual names (OpenImageIO's `compression`), and
// "auto": each product the one that pays for itself. The lossy ones (pxr24, b44, dwaa, dwab)
// would change float32 values and are not offered.
inline constexpr std::array<std::string_view, 6> kExrCompressions = {"auto", "none", "rle",
                                                                     "zips", "zip",  "piz"};
inline constexpr std::string_view kDefaultExrCompression = "auto";

// Visibility-valued products: values in 0..1 with large flat lit and shadowed regions.
inline bool is_visibility_valued(Product kind) {
  return kind == Product::kVisibility || kind == Product::kVisibilityMips ||
         kind == Product::kShadowAtlas || kind == Product::kShadowAtlasMips;
}

// What "auto" writes (docs/decisions/2026-12-07-exr-compression-per-product.md). Visibility:
// zip, 2.9% of the raw bytes in the time rle takes for 35%. Depths, positions, bases and the
// rest: none, as their low mantissa bits do not compress: rle saved 19% of a 4096² shadow map
// for 2.2x the write time, and zip 61% for 5.7x (the 2-core reference machine).
inline std::string_view exr_compression_for(Product kind, std::string_view asked) {
  if (asked != "auto") return asked;
  return is_visibility_valued(kind) ? "zip" : "none";
}

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
