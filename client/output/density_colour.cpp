#include "output/density_colour.hpp"

#include <algorithm>
#include <cmath>

namespace shadow::output {

std::array<uint8_t, 3> density_colour(float v) {
  if (std::isinf(v) && v > 0) return {255, 255, 255};
  // t in [-1, 1]: -1 at 1/16, 0 at 1, 1 at 16.
  const float t = std::clamp(std::log2(std::max(v, 1e-30f)) / 4.0f, -1.0f, 1.0f);
  const auto byte = [](float x) {
    return static_cast<uint8_t>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f));
  };
  if (t < 0) return {0, byte(1.0f + t), byte(-t)};  // blue -> green
  return {byte(t), byte(1.0f - t), 0};              // green -> red
}

}  // namespace shadow::output
