// Where each receiving instance's tile lies in a shadow atlas (PRODUCT_SHADOW_ATLAS): square
// tiles, one per receiving instance, each a power of two sized from the world (a density in world
// units per atlas texel, by default the shadow map's texel footprint on the receiver) or all of
// AtlasSettings::tile texels where the request names one. Pure host code on bounds and matrices:
// validation, the cost estimate, the output size and the bake share it.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "wire/types.hpp"

namespace shadow {

// The tiles sized from a density: powers of two in [kMinDensityTile, kMaxAtlasTile] (and over
// four gutters). An instance that would need more than kMaxAtlasTile gets kMaxAtlasTile.
inline constexpr uint32_t kMinAtlasTile = 16, kMaxAtlasTile = 4096;
// The default density's budget: where the map's footprint would ask for more texels, every tile
// is halved until the atlas fits (a density the request names is never changed: it is refused
// past the device's limits instead).
inline constexpr uint64_t kDefaultAtlasTexels = uint64_t{1} << 24;  // 4096^2
// The atlas' edge limit, whatever sizes its tiles.
inline constexpr uint64_t kMaxAtlasEdge = 16384;
// A layout the server generates (xatlas) packs its charts into part of its square; this share
// stands for its UV area when tiles are sized (the layout is made after the request is
// admitted, the tiles are sized before, and both must agree). Measured on the standard scenes'
// 947 meshes: 0.63 to 0.998 of the square, mean 0.657; taking less than the least keeps every
// generated layout's texels at least as fine as the density.
inline constexpr double kGeneratedUvCoverage = 0.6;

struct AtlasSize {
  uint64_t receivers = 0;          // tiles
  uint64_t width = 0, height = 0;  // texels
};

struct AtlasLayout {
  AtlasSize size;
  std::vector<AtlasTile> tiles;  // in instance order
  // Every tile's x, y and size are multiples of `cell` (the smallest tile): the kernels find a
  // texel's tile in a grid of cells (tile_cells()).
  uint32_t cell = 0;
  uint32_t largest = 0;  // the largest tile
  // Sized from a density: the request's, or the default's with every tile halved this many
  // times to keep within kDefaultAtlasTexels. 0 with a fixed tile.
  uint32_t halved = 0;
};

// The world size that one unit of UV spans on each instance (sqrt of its world area over its
// UV area; a layout the server generates counts as kGeneratedUvCoverage of its square), for the
// receiving instances, 0 for the others. Similarity transforms are exact; other transforms
// scale the mesh's area by |det|^(2/3).
std::vector<double> world_per_uv(const RenderRequest& request);
// The default density per receiving instance (0 for the others): the world size of one shadow
// map texel at its bounds, the finest over the lights (directional: the map fitted to the scene,
// the geometric mean of its texel's two sides; spot and point: the cone's or the cube face's
// texel at the box's point nearest to the light, or at its nearest face from inside).
std::vector<double> map_texel_world_size(const RenderRequest& request);
// The layout the request's atlas takes. Throws nothing: the limits are validate()'s.
AtlasLayout atlas_layout(const RenderRequest& request);
// The layout of tiles of `sizes[i]` texels for the receiving instances (0 for the others),
// powers of two: largest first (ties in instance order), each at its offset along a Z-order
// curve through blocks of the largest tile's side, the blocks in rows of a near-square grid,
// cropped to the tiles. Equal tiles lie in instance order, row by row.
AtlasLayout pack_atlas(const std::vector<uint32_t>& sizes);
// Per cell of `layout` (layout.cell texels square, width / cell per row): the tile over it as
// (x, y, size, 1), or zeros where none is.
std::vector<glm::uvec4> tile_cells(const AtlasLayout& layout);
// The atlas' size (atlas_layout(request).size).
AtlasSize atlas_size(const RenderRequest& request);
// Whether the request asks for the atlas or a product made from it.
bool wants_atlas(const RenderRequest& request);
// Whether the request bakes an atlas: an atlas product or an atlas filter.
bool uses_atlas(const RenderRequest& request);

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
