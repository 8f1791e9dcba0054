// Writes every returned texture to a directory: <name>.exr (float32) and <name>.png (preview).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "wire/types.hpp"

namespace shadow::output {

struct WrittenFile {
  std::filesystem::path path;
  const Texture* texture = nullptr;  // what it holds
  uintmax_t bytes = 0;               // on disk
};

// Creates `dir` if needed. Texture names become file names, so they must be plain names.
// A cube texture becomes one multi-subimage <name>.exr (cube_writer.hpp) and one PNG with its
// faces stacked top to bottom in data order; a cube with no rendered face writes no file.
// Throws std::runtime_error naming the file or directory that failed.
std::vector<WrittenFile> write_products(const std::vector<Texture>& textures,
                                        const std::filesystem::path& dir);

}  // namespace shadow::output
