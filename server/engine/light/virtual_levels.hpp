// A light's virtual map (issue 53; docs/decisions/2026-12-07-virtual-shadow-maps-design.md): its
// levels, pure geometry on a few matrices, in double precision.
//
// A directional light's levels are a clipmap:
// - Level l spans 2^l world units across, in `texels` texels (a power of two), cut into pages of
//   kPageTexels. Levels are absolute: a page's place in the world does not depend on the camera.
// - A level's window (texels across, texels / kPageTexels pages) holds the camera's page in its
//   middle quarter and moves in steps of a quarter: a page's texels are those of a dense map on
//   the window, and stay the same bits while the window, the light and the geometry under the
//   page stand still (the raster's rounding depends on the window's place).
// - Depth is fixed per light: the scene's extent along the light.
//
// A spot light's levels are the mip chain of one perspective map over the scene, mip m a dense map
// of texels >> m texels on the face (the same matrix); a point light's, six such chains, one per
// cube face. A mip's window is its whole face and never moves; its texel, 2^m / texels in mip 0's
// texture NDC, plays a clipmap level's 2^level / texels.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/light/light_space.hpp"
#include "wire/types.hpp"

namespace shadow {

inline constexpr uint32_t kPageTexels = 128;

struct ClipmapLevel {
  int level = 0;          // spans 2^level world units; a perspective map's: its mip
  glm::dvec2 first_page;  // the window's first page in the level's page grid (whole numbers)
  // The dense map on the window: world -> texture NDC, with the light's fixed depth range.
  ViewSetup setup;
};

struct VirtualLevels {
  // 0: a directional light's clipmap; 1: a spot light's mip chain; 6: a point light's, per cube
  // face (face k's mips are levels k * mips .. k * mips + mips - 1).
  int faces = 0;
  int mips = 0;          // levels per face of a perspective map
  glm::dmat4 view{1.0};  // world -> light space, looking along the light; the camera plays no part
  MapDepth depth;        // orthographic: the scene's extent along the light, padded
  // A perspective map's faces: world -> mip 0's texture NDC (all zeros for a face that decides
  // nothing), and how a pixel picks its face (a point light's).
  std::vector<glm::dmat4> face_ndc;
  CubeFaces cube;
  uint32_t texels = 0;               // across each level
  std::vector<ClipmapLevel> levels;  // first_level .. last_level, finest first; or per face
  bool perspective() const { return faces > 0; }
  // Level i's texels across: a clipmap level's window, or a mip's texture. Its page table holds
  // (extent / kPageTexels)^2 pages in rows of extent / kPageTexels.
  uint32_t extent(size_t i) const { return perspective() ? texels >> levels[i].level : texels; }
};

// World units across one texel of level `level` at `texels` texels a level.
double clipmap_texel(int level, uint32_t texels);

// The coarsest level whose texel is at most `footprint` (world units, > 0) times 2^bias: the
// level a pixel of that footprint in light space reads (at least a texel per pixel at bias 0).
int clipmap_level(double footprint, double bias, uint32_t texels);

// Levels first_level .. last_level of `light` (directional) around `eye`, over `scene` (world
// bounds of everything that casts or receives).
VirtualLevels directional_clipmap(const Light& light, const glm::dvec3& eye, const Bounds& scene,
                                  uint32_t texels, int first_level, int last_level);

// Pixel filters reach at most this many texels of a pixel's level (PCF, Poisson's radius); PCSS's
// blocker search at most kMaxSoftReach (its level is chosen for it). Both under a page: marking
// gives a pixel the pages of its taps' square's corners. The coarsest level's window holds every
// receiver with the filter's margin.
inline constexpr uint32_t kMaxReach = 16;
inline constexpr uint32_t kMaxSoftReach = 64;
// At most this many levels (pcf.cl's VIRTUAL keeps a bit per level present in a strip).
inline constexpr int kMaxLevels = 32;

// The clipmap a view of `camera` needs: the coarsest level is the first whose window (around
// the camera's page) holds all of `scene` with `margin` texels to spare, so that every
// receiver has a level, or coarser, to the level of the scene's farthest pixel; the finest is
// the level of a pixel at the near plane (no pixel's footprint is smaller); at most kMaxLevels.
VirtualLevels fit_directional_clipmap(const Light& light, const Camera& camera, const Bounds& scene,
                                      uint32_t texels, double bias, uint32_t margin = kMaxReach);

// The mips of a perspective map of `texels` texels that a light of `type` (spot or point) keeps:
// down to a page for a spot light; for a point light at most kMaxLevels / 6, so that its six
// faces' levels fit.
int virtual_mips(LightType type, uint32_t texels);

// The levels of perspective maps `faces` (a spot light's one, or a point light's six cube faces
// with `cube`, how pixels pick them), each at texels >> m for m < `mips`.
VirtualLevels perspective_levels(const std::vector<ViewSetup>& faces, const CubeFaces& cube,
                                 uint32_t texels, int mips);

}  // namespace shadow
