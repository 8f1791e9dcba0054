// The prefilters' CPU references, shared by prefilter_test.cpp (each pass against them) and
// prefilter_shapes_test.cpp (the GPU shape against them): a float image, box sums summed directly
// in long double, and one mip level of the area-weighted box filter in double, NaN left out.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace shadow::testing {

struct Image {
  uint32_t w, h, c;
  std::vector<float> v;
  float at(uint32_t x, uint32_t y, uint32_t ch) const { return v[(size_t{y} * w + x) * c + ch]; }
};

// The sum of channel `ch` over the inclusive box (x0, y0)..(x1, y1), NaN texels left out.
inline long double box_direct(const Image& im, uint32_t ch, int x0, int y0, int x1, int y1) {
  long double s = 0;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const float v = im.at(x, y, ch);
      if (!std::isnan(v)) s += v;
    }
  return s;
}

// One level of the area-weighted box filter in double (w x h -> w2 x h2, c channels), NaN left
// out; NaN where a texel's whole footprint is.
inline std::vector<double> cpu_downsample(const std::vector<double>& src, uint32_t w, uint32_t h,
                                          uint32_t c, uint32_t w2, uint32_t h2) {
  std::vector<double> out(size_t{w2} * h2 * c);
  for (uint32_t j = 0; j < h2; ++j)
    for (uint32_t i = 0; i < w2; ++i)
      for (uint32_t ch = 0; ch < c; ++ch) {
        double s = 0, ws = 0;
        const double x0 = double(i) * w / w2, x1 = double(i + 1) * w / w2;
        const double y0 = double(j) * h / h2, y1 = double(j + 1) * h / h2;
        for (uint32_t y = uint32_t(y0); y < std::ceil(y1); ++y)
          for (uint32_t x = uint32_t(x0); x < std::ceil(x1); ++x) {
            const double wt = (std::min<double>(x + 1, x1) - std::max<double>(x, x0)) *
                              (std::min<double>(y + 1, y1) - std::max<double>(y, y0));
            const double v = src[(size_t{y} * w + x) * c + ch];
            if (!std::isnan(v) && wt > 0) s += wt * v, ws += wt;
          }
        out[(size_t{j} * w2 + i) * c + ch] = ws > 0 ? s / ws : NAN;
      }
  return out;
}

}  // namespace shadow::testing
