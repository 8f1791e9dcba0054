// Writes every returned texture to a directory: <name>.exr (float32) and <name>.png (preview).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "output/output_options.hpp"
#include "wire/types.hpp"

namespace shadow::output {

struct WrittenFile {
  std::filesystem::path path;
  const Texture* texture = nullptr;  // what it holds
  uintmax_t bytes = 0;               // on disk
};

// `dir` / <name>.exr for a texture; throws std::runtime_error unless the name is a plain file
// name (names come from the wire and must not escape the directory).
std::filesystem::path exr_path(const Texture& texture, const std::filesystem::path& dir);

// True for a texture written as a single-part float32 EXR (not a cube, mip level or SAT): the
// kind StreamWriter writes row by row as it arrives.
bool is_plain(const Texture& texture);

// Creates `dir` if needed. Texture names become file names, so they must be plain names.
// A cube texture becomes one multi-subimage <name>.exr (cube_writer.hpp) and one PNG with its
// faces stacked top to bottom in data order; a cube with no rendered face writes no file.
// Textures flagged in `exr_written` (same indices; e.g. by StreamWriter) get only their PNG.
// Throws std::runtime_error naming the file or directory that failed.
std::vector<WrittenFile> write_products(const std::vector<Texture>& textures,
                                        const std::filesystem::path& dir,
                                        const OutputOptions& options = {},
                                        const std::vector<bool>& exr_written = {});

}  // namespace shadow::output
