// Perspective Shadow Maps: the light's frustum fitted in the camera's post-perspective space
// (Stamminger & Drettakis 2002; Kozlov, GPU Gems ch. 14). Pure math, double precision.
//
// The result is one world -> texture-NDC matrix M = T * Lview * C': C' is a virtual camera's GL
// projection * view (the request's camera with its near plane pushed to the visible receivers
// and its far plane pulled to them, optionally slid back), Lview looks from the light's
// post-perspective position at the receivers, and T maps light-view homogeneous coordinates to
// texture clip space. Every row stays homogeneous, so points behind the camera (clip w < 0) that
// land behind an inverted light come out with a positive final w and are rasterized.
//
// Cases (post_perspective_light on C'):
//   point (directional from the front): perspective, near = the nearest caster inside the
//     receivers' pyramid, far = the farthest receiver.
//   inverted point (directional from behind), casters by the inverse projection (Kozlov 14.1.1):
//     light-view depth z -> (1 + a / z) / 2, i.e. 0 at z = -a, 1/2 at +-infinity, 1 at z = a;
//     casters behind the camera sit behind the light (z <= -a), receivers at z >= a.
//   inverted point, slide-back (the paper, section 4.2): the virtual camera moves back until no
//     caster is behind it; depth is then reversed, 0 at the farthest caster, 1 at the nearest
//     receiver.
//   directional (light parallel to the image plane): orthographic in post-perspective space.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "engine/light/cube_fit.hpp"
#include "engine/light/light_space.hpp"
#include "wire/types.hpp"

namespace shadow {

struct PsmFit {
  ViewSetup setup;          // view = the virtual camera's view (the light has no world view)
  std::string light_case;   // e.g. "directional from behind: inverted point light"
  double virtual_near = 0;  // the virtual camera's near/far (world units along its axis)
  double virtual_far = 0;
  double slide_back = 0;        // how far the virtual camera moved back (world units), 0 if not:
                                // the casters' slide-back plus the virtual one
  double virtual_slide = 0;     // PsmNear::kVirtualSlideBack: its share of slide_back
  double virtual_fovy_deg = 0;  // the virtual camera's vertical field of view
  double light_near = 0;        // the light's near and far in post-perspective light-view depth;
  double light_far = 0;         // for the inverse projection: near = -a, far = a
  // A spot or point light inside (or next to) the receivers' post-perspective box: no single
  // frustum sees them all. Spot: `setup` is the uniform spot map; point: `setup` is unset and
  // the light needs cube faces.
  bool needs_cube = false;
};

// The visible receivers' depth range measured on the camera view (engine/passes/depth_range.*):
// distances from the request camera's eye along its forward axis.
struct DepthRange {
  double min = 0;
  double max = 0;
};

// Any light position: directional, spot (receivers also clipped to its cone's pyramid) and point
// (inside the view it needs_cube: the engine renders the point light's cube instead). With
// `measured` and psm.near = kReceivers or kVirtualSlideBack, the virtual near/far planes come from
// the measured range (widened by 1e-3 of itself) instead of the receivers' bounding boxes; the
// light is still aimed at the bounding boxes clipped to the view frustum (unit-cube clipping).
// `min_caster_distance`: a lower bound of the distance from a spot or point light to every
// caster triangle (passes/light_distance), read only where a caster's box holds the light (a
// lamp in a room that is one mesh): it bounds the near plane there. Without it such a box's
// casters count from 1e-4 of the receivers' light depth, and the depth range is that small.
PsmFit fit_psm_light(const Light& light, const Camera& camera,
                     const std::vector<InstanceBounds>& instances, const PsmSettings& settings,
                     const std::optional<DepthRange>& measured = std::nullopt,
                     std::optional<double> min_caster_distance = std::nullopt);

// Whether a caster's box holds the (spot or point) light: where the fits read
// `min_caster_distance`.
bool caster_box_holds_light(const Light& light, const std::vector<InstanceBounds>& instances);

// PSM's cube-map approach (Kozlov 14.2.2): in post-perspective space, one perspective face from
// the light through each side of the unit cube that faces away from it (3 to 5 for a light
// outside the cube, all 6 inside), each aimed at the part of the visible receivers' box seen
// through that side (unit-cube clipping per face) and widened by `guard` texels. A camera pixel
// belongs to the side where the line from the light through it leaves the cube (listing 14-1;
// CubeFaces with space = the virtual camera's clip space). Depth per face as for the single
// map (perspective_depth: a point light, or the inverted light through infinity), with the
// near planes bounded by `min_caster_distance` as for fit_psm_light.
struct PsmCubeFit {
  bool cube = false;  // false: `fit` is the whole single-map fit (see below)
  // cube: the virtual camera's numbers and the case; else the single map, used where the light
  // is parallel in post-perspective space (orthographic, PSM's best case needs no cube) or
  // where there is no visible receiver (a point light's fit then needs_cube, the omni cube).
  PsmFit fit;
  std::array<CubeFaceFit, 6> faces;
  // The rendered faces' texels on their sides of the unit cube, as a fraction of its edge.
  double texel_min = 0, texel_max = 0;
};

PsmCubeFit fit_psm_cube(const Light& light, const Camera& camera,
                        const std::vector<InstanceBounds>& instances, const PsmSettings& settings,
                        const std::optional<DepthRange>& measured, uint32_t map_size,
                        uint32_t guard, std::optional<double> min_caster_distance = std::nullopt);

}  // namespace shadow
