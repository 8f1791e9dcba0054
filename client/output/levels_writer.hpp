// Multi-texture products as files: a mip chain (one texture per level) as one multi-part EXR,
// and a float64 summed-area table as float32 hi + lo channels (EXR has no float64).
#pragma once

#include <filesystem>
#include <vector>

#include "output/output_options.hpp"
#include "wire/types.hpp"

namespace shadow::output {

// True for the kinds whose textures are mip levels ("<name>_mip<i>").
bool is_mip_level(const Texture& t);

// Writes `levels` (level 0 first) as one EXR with a part per level, named "mip<i>", each with
// the level's matrices. Throws std::runtime_error naming the file.
void write_mip_exr(const std::vector<const Texture*>& levels, const std::filesystem::path& file,
                   std::string_view compression = kDefaultExrCompression);

// A float64 texture as float32 with twice the channels: hi = float(v), lo = float(v - hi), so
// hi + lo (added in double) carries 48 significant bits of v. Channel names "<c>.hi", "<c>.lo".
Texture split_hi_lo(const Texture& t);

}  // namespace shadow::output
