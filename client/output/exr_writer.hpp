// One texture as a float32 (or, for float16 textures, half) OpenEXR file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "output/output_options.hpp"
#include "wire/types.hpp"

namespace shadow::output {

// Channel names by product: shadow map "Z", visibility "Y", position "R","G","B".
std::vector<std::string> channel_names(const Texture& texture);

// Writes the texture's floats unchanged (NaN stays NaN) with OpenEXR's standard attributes
// `worldToNDC` and `worldToCamera` (m44f, row-vector convention p · M: the transpose of the
// engine's column-major matrices; OpenImageIO reads them as worldtoNDC and worldtocamera) and,
// for shadow maps, `textureformat` = "Shadow". `compression` is a name from kExrCompressions (all
// lossless). Throws std::runtime_error naming the file.
void write_exr(const Texture& texture, const std::filesystem::path& file,
               std::string_view compression = kDefaultExrCompression);

}  // namespace shadow::output
