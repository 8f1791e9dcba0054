#include "output/png_preview.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>

#include <png.h>

#include "output/density_colour.hpp"
#include "output/fresh_file.hpp"
#include "output/output_options.hpp"

namespace shadow::output {
namespace {

// std::lround of the float product, without a libm call per pixel: the product is in
// [0, 255], where adding 0.5 in double is exact.
uint8_t unit_grey(float v) {
  return static_cast<uint8_t>(double(std::clamp(v, 0.0f, 1.0f) * 255.0f) + 0.5);
}

struct Range {
  float lo = std::numeric_limits<float>::infinity();
  float hi = -std::numeric_limits<float>::infinity();
  void add(float v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  uint8_t map(float v) const { return unit_grey(hi > lo ? (v - lo) / (hi - lo) : 0.0f); }
};

constexpr int kPngLevel = 1;

// Every k-th texel of each face, k the smallest that brings the longer side to at most `edge`,
// with the fields preview_rgb8 reads; nothing when the texture is that small already.
std::optional<Texture> preview_sized(const Texture& t, uint32_t edge) {
  const uint32_t longer = std::max(t.width, t.height);
  if (edge == 0 || longer <= edge) return std::nullopt;
  const uint32_t k = (longer + edge - 1) / edge;
  Texture out;  // what a preview reads, not a copy of the (large) texture
  out.name = t.name;
  out.kind = t.kind;
  out.channels = t.channels;
  out.faces = t.faces;
  out.width = (t.width + k - 1) / k;
  out.height = (t.height + k - 1) / k;
  const size_t nc = t.channels;
  out.data.assign(size_t{out.width} * out.height * t.faces * nc, 0.0f);
  for (uint32_t f = 0; f < t.faces; ++f)
    for (uint32_t y = 0; y < out.height; ++y)
      for (uint32_t x = 0; x < out.width; ++x) {
        const size_t from = ((size_t{f} * t.height + size_t{y} * k) * t.width + size_t{x} * k) * nc;
        const size_t to = ((size_t{f} * out.height + y) * out.width + x) * nc;
        std::copy_n(t.data.begin() + from, nc, out.data.begin() + to);
      }
  return out;
}

bool is_grey(const std::vector<uint8_t>& rgb) {
  for (size_t i = 0; i < rgb.size(); i += 3)
    if (rgb[i] != rgb[i + 1] || rgb[i] != rgb[i + 2]) return false;
  return true;
}

// Writes 8-bit grey (1 channel) or RGB (3) pixels, row 0 at the top.
void write_png(const std::filesystem::path& file, const uint8_t* pixels, uint32_t width,
               uint32_t height, uint32_t channels) {
  const size_t row_bytes = size_t{width} * channels;
  remove_old_file(file);
  FILE* out = std::fopen(file.c_str(), "wb");
  if (!out) throw std::runtime_error(file.string() + ": cannot open for writing");
  // libpng reports errors by longjmp: nothing with a destructor lives between here and there.
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(out);
    throw std::runtime_error(file.string() + ": cannot write the PNG");
  }
  png_init_io(png, out);
  // zlib's fastest level: a 4096² preview took seconds at libpng's default 6 (docs/benchmarks.md).
  png_set_compression_level(png, kPngLevel);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);  // one filter, not all five per row
  png_set_IHDR(png, info, width, height, 8,
               channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (uint32_t y = 0; y < height; ++y) png_write_row(png, pixels + y * row_bytes);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(out) != 0) throw std::runtime_error(file.string() + ": cannot write the PNG");
}

}  // namespace

std::vector<uint8_t> preview_rgb8(const Texture& t) {
  const size_t pixels = size_t{t.width} * t.height * t.faces;
  const uint32_t nc = t.channels;
  if (nc == 0 || t.data.size() != pixels * nc)
    throw std::runtime_error("preview of '" + t.name + "': data size does not match its shape");
  std::vector<uint8_t> rgb(pixels * 3);
  const auto put_nothing = [&](size_t p) {
    std::copy(kNothingColour.begin(), kNothingColour.end(), rgb.begin() + 3 * p);
  };

  if ((t.kind == Product::kShadowMap || t.kind == Product::kShadowMapMips) && nc == 1) {
    Range r;
    for (float v : t.data)
      if (std::isfinite(v) && v < 1.0f) r.add(v);
    for (size_t p = 0; p < pixels; ++p) {
      const float v = t.data[p];
      const uint8_t g = !std::isfinite(v) || v >= 1.0f ? 255 : r.map(v);
      std::fill_n(rgb.begin() + 3 * p, 3, g);
    }
  } else if (is_visibility_valued(t.kind) && nc == 1) {
    for (size_t p = 0; p < pixels; ++p) {
      if (std::isnan(t.data[p]))
        put_nothing(p);
      else
        std::fill_n(rgb.begin() + 3 * p, 3, unit_grey(t.data[p]));
    }
  } else if (t.kind == Product::kTexelDensity && nc == 1) {
    for (size_t p = 0; p < pixels; ++p) {
      if (std::isnan(t.data[p])) {
        put_nothing(p);
      } else {
        const auto c = density_colour(t.data[p]);
        std::copy(c.begin(), c.end(), rgb.begin() + 3 * p);
      }
    }
  } else {
    std::vector<Range> r(nc);
    for (size_t i = 0; i < t.data.size(); ++i)
      if (std::isfinite(t.data[i])) r[i % nc].add(t.data[i]);
    for (size_t p = 0; p < pixels; ++p) {
      const float* v = &t.data[p * nc];
      if (std::any_of(v, v + nc, [](float x) { return std::isnan(x); })) {
        put_nothing(p);
        continue;
      }
      for (uint32_t c = 0; c < 3; ++c) {
        const uint32_t src = std::min(c, nc - 1);  // one channel → grey
        rgb[3 * p + c] = r[src].map(v[src]);
      }
    }
  }
  return rgb;
}

void write_png_preview(const Texture& full, const std::filesystem::path& file, uint32_t edge) {
  const std::optional<Texture> sized = preview_sized(full, edge);
  const Texture& texture = sized ? *sized : full;
  std::vector<uint8_t> pixels = preview_rgb8(texture);
  const uint32_t width = texture.width, height = texture.height * texture.faces;
  // A grey preview (shadow maps, visibility without holes) is written with one channel: a third
  // of the bytes for zlib, which is most of a preview's time.
  const bool grey = is_grey(pixels);
  if (grey) {
    const size_t count = size_t{width} * height;
    for (size_t p = 0; p < count; ++p) pixels[p] = pixels[3 * p];
    pixels.resize(count);
  }
  write_png(file, pixels.data(), width, height, grey ? 1 : 3);
}

}  // namespace shadow::output
