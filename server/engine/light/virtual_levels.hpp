// A directional light's virtual clipmap (issue 53; docs/decisions/2026-12-07-virtual-shadow-maps-
// design.md): pure geometry on a few matrices, in double precision.
// - Level l spans 2^l world units across, in `texels` texels (a power of two), cut into pages of
//   kPageTexels. Levels are absolute: a page's place in the world does not depend on the camera.
// - A level's window (texels across, texels / kPageTexels pages) holds the camera's page in its
//   middle quarter and moves in steps of a quarter: a page's texels are those of a dense map on
//   the window, and stay the same bits while the window, the light and the geometry under the
//   page stand still (the raster's rounding depends on the window's place).
// - Depth is fixed per light: the scene's extent along the light.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/light/light_space.hpp"
#include "wire/types.hpp"

namespace shadow {

inline constexpr uint32_t kPageTexels = 128;

struct ClipmapLevel {
  int level = 0;          // spans 2^level world units
  glm::dvec2 first_page;  // the window's first page in the level's page grid (whole numbers)
  // The dense map on the window: world -> texture NDC, with the light's fixed depth range.
  ViewSetup setup;
};

struct DirectionalClipmap {
  glm::dmat4 view{1.0};  // world -> light space, looking along the light; the camera plays no part
  MapDepth depth;        // orthographic: the scene's extent along the light, padded
  uint32_t texels = 0;   // across each level
  std::vector<ClipmapLevel> levels;  // first_level .. last_level, finest first
};

// World units across one texel of level `level` at `texels` texels a level.
double clipmap_texel(int level, uint32_t texels);

// The coarsest level whose texel is at most `footprint` (world units, > 0) times 2^bias: the
// level a pixel of that footprint in light space reads (at least a texel per pixel at bias 0).
int clipmap_level(double footprint, double bias, uint32_t texels);

// Levels first_level .. last_level of `light` (directional) around `eye`, over `scene` (world
// bounds of everything that casts or receives).
DirectionalClipmap directional_clipmap(const Light& light, const glm::dvec3& eye,
                                       const Bounds& scene, uint32_t texels, int first_level,
                                       int last_level);

// Pixel filters reach at most this many texels (PCF, Poisson's radius): the coarsest level's
// window holds every receiver with this margin.
inline constexpr uint32_t kMaxReach = 16;
// At most this many levels (pcf.cl's VIRTUAL keeps a bit per level present in a strip).
inline constexpr int kMaxLevels = 32;

// The clipmap a view of `camera` needs: the coarsest level is the first whose window (around
// the camera's page) holds all of `scene` with kMaxReach texels to spare, so that every
// receiver has a level, or coarser, to the level of the scene's farthest pixel; the finest is
// the level of a pixel at the near plane (no pixel's footprint is smaller); at most kMaxLevels.
DirectionalClipmap fit_directional_clipmap(const Light& light, const Camera& camera,
                                           const Bounds& scene, uint32_t texels, double bias);

}  // namespace shadow
