// Colour map for texel-density previews: how many pixels one shadow-map texel spans.
#pragma once

#include <array>
#include <cstdint>

namespace shadow::output {

// log2 scale from 1/16 (blue: the map over-samples) through 1 (green) to 16 (red: one texel
// spans 16 pixels, blocky shadow edges); +inf (grazing light) is white.
std::array<uint8_t, 3> density_colour(float texels_per_pixel);

}  // namespace shadow::output
