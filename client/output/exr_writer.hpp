// One texture as a float32 OpenEXR file through OpenImageIO.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "wire/types.hpp"

namespace shadow::output {

// Channel names by product: shadow map "Z", visibility "Y", position "R","G","B".
std::vector<std::string> channel_names(const Texture& texture);

// Writes the texture's floats unchanged (NaN stays NaN) with the attributes `worldtoNDC` and
// `worldtocamera` as OIIO matrix44 in its row-vector convention (p · M, the transpose of the
// engine's column-major matrices) and, for shadow maps, `textureformat` = "Shadow". OpenEXR
// stores the matrices under its own names worldToNDC / worldToCamera; OIIO's attribute lookup
// is case-insensitive. Throws std::runtime_error naming the file.
void write_exr(const Texture& texture, const std::filesystem::path& file);

}  // namespace shadow::output
