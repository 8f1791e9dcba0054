// One texture as a float32 OpenEXR file through OpenImageIO.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "output/output_options.hpp"
#include "wire/types.hpp"

namespace shadow::output {

// Channel names by product: shadow map "Z", visibility "Y", position "R","G","B".
std::vector<std::string> channel_names(const Texture& texture);

// Writes the texture's floats unchanged (NaN stays NaN) with the attributes `worldtoNDC` and
// `worldtocamera` as OIIO matrix44 in its row-vector convention (p · M, the transpose of the
// engine's column-major matrices) and, for shadow maps, `textureformat` = "Shadow". OpenEXR
// stores the matrices under its own names worldToNDC / worldToCamera; OIIO's attribute lookup
// is case-insensitive. `compression` is a name from kExrCompressions (all lossless). Throws
// std::runtime_error naming the file.
void write_exr(const Texture& texture, const std::filesystem::path& file,
               std::string_view compression = kDefaultExrCompression);

}  // namespace shadow::output
