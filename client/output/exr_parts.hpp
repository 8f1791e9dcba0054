// Internal to shadow_output (includes OpenEXR): a texture as an EXR part (its header and where
// its pixels are), and writing one or several parts (a mip chain's levels, a cube's faces) to one
// file.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include <Imath/half.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>

#include "output/output_options.hpp"
#include "wire/types.hpp"

namespace shadow::output {

struct ExrPart {
  Imf::Header header;
  Imf::FrameBuffer pixels;
  // A float16 texture's values as halves, which `pixels` reads (OpenEXR converts nothing on
  // output); shared, so that a copy of the part reads the same.
  std::shared_ptr<std::vector<half>> halves;
};

// The texture's header (size, channels: HALF for float16 textures, else FLOAT; `compression`, a
// name from kExrCompressions; its matrices and, for shadow maps, textureformat "Shadow":
// exr_writer.cpp), reading its float32 rows, channels interleaved, from `pixels`.
ExrPart exr_part(const Texture& texture, std::string_view compression, const float* pixels);

// Writes the parts: one as an ordinary scanline file, several as a multi-part file (each part
// then needs a "name"). Throws std::runtime_error naming the file.
void write_exr_parts(const std::filesystem::path& file, const std::vector<ExrPart>& parts);

// OpenEXR compresses a file's blocks on every core (once per process).
void use_every_core();

}  // namespace shadow::output
