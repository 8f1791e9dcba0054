// 8-bit previews of float textures, for looking at, not for measuring.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "wire/types.hpp"

namespace shadow::output {

// Pixels with no value (NaN) in visibility and position previews: a muted blue that neither
// grey visibility nor normalized positions hit by accident in the demo.
inline constexpr std::array<uint8_t, 3> kNothingColour = {64, 96, 160};

// RGB8, row 0 at the top. Shadow map: grey, normalized to the finite depths below 1.0 (the
// cleared value; such texels are white). Visibility: grey 0..1. Position and anything else:
// each channel normalized to its own finite min..max. Texel density: density_colour (log2,
// blue < 1 < red). NaN → kNothingColour.
std::vector<uint8_t> preview_rgb8(const Texture& texture);

// Writes preview_rgb8(texture) as a PNG of at most `edge` pixels along its longer side (every
// k-th texel of each face; 0: every texel), grey (one channel) when every pixel is grey.
// Throws std::runtime_error naming the file.
void write_png_preview(const Texture& texture, const std::filesystem::path& file,
                       uint32_t edge = 0);

}  // namespace shadow::output
