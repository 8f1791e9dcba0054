// Internal to shadow_output (includes OpenImageIO): the EXR spec of a texture, and writing
// several parts (subimages) to one EXR, for the mip-chain and cube writers.
#pragma once

#include <filesystem>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "output/output_options.hpp"
#include "wire/types.hpp"

namespace shadow::output {

// The float32 spec of a texture: size, channel names, `compression` (a name from
// kExrCompressions), its matrices and, for shadow maps, textureformat "Shadow" (exr_writer.cpp).
OIIO::ImageSpec exr_spec(const Texture& texture, std::string_view compression);

// Writes part i with specs[i] from the float32 pixels at pixels[i] (the spec's full size,
// row-major, channels interleaved). Throws std::runtime_error naming the file.
void write_exr_parts(const std::filesystem::path& file, const std::vector<OIIO::ImageSpec>& specs,
                     const std::vector<const float*>& pixels);

}  // namespace shadow::output
