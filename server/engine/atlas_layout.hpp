// Where each receiving instance's tile lies in a shadow atlas (PRODUCT_SHADOW_ATLAS): square
// tiles of AtlasSettings::tile texels, in instance order, row by row in a near-square grid.
// Pure host code: validation, the output size and the bake share it.
#pragma once

#include <cstdint>
#include <vector>

#include "wire/types.hpp"

namespace shadow {

struct AtlasSize {
  uint64_t receivers = 0;  // tiles
  uint64_t columns = 0;
  uint64_t width = 0, height = 0;  // texels
};

// The atlas' size, from counts alone (validation checks it before any tile is listed).
AtlasSize atlas_size(const Scene& scene, const AtlasSettings& settings);
// Whether the request asks for the atlas or a product made from it.
bool wants_atlas(const RenderRequest& request);
// FILTER_ATLAS_SAT and FILTER_ATLAS_MIP: VISIBILITY read from the prefiltered atlas.
bool is_atlas_filter(FilterKind kind);
// Whether the request bakes an atlas: an atlas product or an atlas filter.
bool uses_atlas(const RenderRequest& request);
// Every tile, in instance order; call once atlas_size() has been validated.
std::vector<AtlasTile> atlas_tiles(const Scene& scene, const AtlasSettings& settings);

// The UV charts of a mesh with UVs: triangles joined where they share a corner that is the same
// point on the surface and in UV space (equal position and UV), as lightmap bakers split their
// filters. Per triangle its chart, 0 .. count - 1, in order of first appearance.
struct UvCharts {
  std::vector<uint32_t> of_triangle;
  uint32_t count = 0;
};
UvCharts uv_charts(const Mesh& mesh);
// Whether every UV triangle of the mesh has zero area (every face mapped to one point or line):
// such a layout covers no atlas texel.
bool uvs_degenerate(const Mesh& mesh);

}  // namespace shadow
