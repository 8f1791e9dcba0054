#include "output/png_preview.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <OpenImageIO/imageio.h>

#include "output/density_colour.hpp"

namespace shadow::output {
namespace {

struct Range {
  float lo = std::numeric_limits<float>::infinity();
  float hi = -std::numeric_limits<float>::infinity();
  void add(float v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  uint8_t map(float v) const {
    const float t = hi > lo ? (v - lo) / (hi - lo) : 0.0f;
    return static_cast<uint8_t>(std::lround(std::clamp(t, 0.0f, 1.0f) * 255.0f));
  }
};

constexpr int kPngLevel = 1;

uint8_t unit_grey(float v) {
  return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
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
  } else if ((t.kind == Product::kVisibility || t.kind == Product::kVisibilityMips ||
              t.kind == Product::kShadowAtlas || t.kind == Product::kShadowAtlasMips) &&
             nc == 1) {
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

void write_png_preview(const Texture& texture, const std::filesystem::path& file) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(file.string() + ": " + why);
  };
  const std::vector<uint8_t> rgb = preview_rgb8(texture);
  OIIO::ImageSpec spec(static_cast<int>(texture.width),
                       static_cast<int>(texture.height * texture.faces), 3, OIIO::TypeDesc::UINT8);
  // zlib's fastest level: a 4096² preview took seconds at libpng's default 6 (docs/benchmarks.md).
  spec.attribute("png:compressionLevel", kPngLevel);
  auto out = OIIO::ImageOutput::create(file.string());
  if (!out) fail("cannot create a PNG writer: " + OIIO::geterror());
  if (!out->open(file.string(), spec)) fail(out->geterror());
  if (!out->write_image(OIIO::TypeDesc::UINT8, rgb.data())) fail(out->geterror());
  if (!out->close()) fail(out->geterror());
}

}  // namespace shadow::output
