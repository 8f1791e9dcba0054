// shadow-atlas-bench --standard: the atlas filters against PCSS, the hard test and the Embree
// area-light oracle on the standard scenes (tests/oracle/standard_scenes.hpp), in UVs the server
// lays out (AtlasSettings::generate_uvs: the scenes' own UVs tile their textures).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/engine.hpp"

namespace shadow::bench {

// Mean |error| over the pixels where `select` is `want` (both finite); `count` of them.
inline double mean_error(const std::vector<float>& got, const std::vector<float>& truth,
                         const std::vector<uint8_t>& select, uint8_t want, size_t& count) {
  double sum = 0;
  count = 0;
  for (size_t p = 0; p < got.size(); ++p)
    if (select[p] == want && std::isfinite(got[p]) && std::isfinite(truth[p]))
      sum += std::abs(got[p] - truth[p]), ++count;
  return count ? sum / count : 0.0;
}

struct StandardOptions {
  uint32_t map = 2048, tile = 256;  // tile 0: tiles sized from the world
  double density = 0;               // with tile 0: world units a texel, 0 = the map's footprint
  std::vector<std::string> scenes;  // names to run; empty: all
  // Where to write each view's 640x360 images (DIR/<scene>_<view>_<name>.f32): the oracle,
  // each technique, and per pixel the continuous atlas texel its point falls in (qx, qy; NaN
  // where none) beside the hard atlas with and without its gutter (scripts/plot_atlas.py).
  std::string images;
};

// Every view of a standard scene whose light has a size and is not a point light (the atlas
// filters take uniform maps), at 640x360: hard, pcss, atlas_sat and atlas_mip, each one render's
// device time (frame: G-buffer and visibility; bake: the rest) and its error against the
// area-light oracle: overall, over the penumbra, on the pixels the oracle sees fully lit, and
// within 4 atlas texels of a chart's border or not. Prints a Markdown table.
void standard_scenes_table(Engine& engine, const StandardOptions& options);

}  // namespace shadow::bench
