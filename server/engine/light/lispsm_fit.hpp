// Light Space Perspective Shadow Maps (Wimmer, Scherzer, Purgathofer 2004) for a directional
// light. Pure math, double precision.
//
// Light space: x across, y = the view direction projected onto the plane perpendicular to the
// light, z towards the light. LiSPSM puts a perspective "warp" frustum P in light space that
// looks along +y: its centre sits n behind the visible receivers' nearest y, so near the viewer
// (small y) texels shrink as 1/distance, as in PSM, while the light stays a directional light
// after the warp (its rays are parallel to z, which P divides by the same y-distance). The map
// is orthographic in warped space: u = (x - x_c)/s, v = the warp's depth (s = y - y_c), map depth
// (t - t_min)/s with t the depth along the light. Every vertex of the receivers and of the
// casters over them has s >= n > 0, so nothing is behind the warp's centre.
//
// n (Wimmer's eq. for the optimal warp, generalized to any light angle gamma between the light
// and the view direction): n_opt = (z_n + sqrt(z_n z_f)) / sin(gamma), z_n, z_f the visible
// receivers' view-depth range (measured on the camera view when the plan has it). The 1/sin
// is the falloff: as the light turns towards the view direction (or away from it, light behind)
// n grows and the warp fades to the uniform map; past n > 1e4 * the receivers' y-extent the
// warp changes texel sizes by < 1e-4 and the fit is the orthographic map itself.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "engine/light/light_space.hpp"
#include "engine/light/psm_fit.hpp"  // DepthRange
#include "wire/types.hpp"

namespace shadow {

struct LispsmFit {
  ViewSetup setup;         // view = the light's view (rigid), world_to_ndc = the warped map
  std::string light_case;  // "lispsm: n 12.3 (n_opt), gamma 45.0 deg"
  double n = 0;            // the warp's near distance used; 0 = orthographic (no warp)
  double n_opt = 0;        // Wimmer's n_opt for this view (inf when the light is along the view)
  double gamma_deg = 0;    // angle between the light's travel and the view direction
};

// Directional lights only (validation rejects others). settings.n > 0 overrides n_opt.
LispsmFit fit_lispsm_light(const Light& light, const Camera& camera,
                           const std::vector<InstanceBounds>& instances,
                           const LispsmSettings& settings,
                           const std::optional<DepthRange>& measured = std::nullopt);

}  // namespace shadow
