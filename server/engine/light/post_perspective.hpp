// Perspective Shadow Maps, step one: the light as seen in the camera's post-perspective space
// (Stamminger & Drettakis 2002, §3; Kozlov, GPU Gems ch. 14). Pure math, double precision.
//
// The camera's projection maps the world to clip space and, after division by w, the view
// frustum to the unit cube. A light maps to a homogeneous point L = P V (l, w_l), with
// (l, w_l) = (position, 1) for a point light and (-direction, 0) (towards the light, at
// infinity) for a directional one. The sign of L.w decides the case:
//   L.w > 0  an ordinary point light at L.xyz / L.w (a directional light from the front lands
//            on the plane at infinity, z = (f + n) / (f - n));
//   L.w < 0  an inverted point light: it sits at L.xyz / L.w but its rays run backwards, so
//            the depth order is reversed (a directional light from behind, a point light
//            behind the camera);
//   L.w = 0  a directional light in post-perspective space (a directional light parallel to
//            the image plane, a point light in the camera plane).
// The boundary is taken relative to |L.xyz| so that no case divides by a vanishing w.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "wire/types.hpp"

namespace shadow {

enum class PostPerspectiveCase { kPoint, kInvertedPoint, kDirectional };

struct PostPerspectiveLight {
  PostPerspectiveCase kind = PostPerspectiveCase::kPoint;
  glm::dvec4 homogeneous{0.0};  // P V (l, w_l), unnormalized
  glm::dvec3 position{0.0};     // NDC ([-1, 1]^3, GL); point cases only
  glm::dvec3 direction{0.0};    // NDC direction of travel; directional case only
  std::string description;      // e.g. "directional from behind: inverted point light"
};

// `world_to_clip` is the camera's GL projection times view (NDC in [-1, 1]^3).
// |L.w| <= `parallel_tolerance` * |L.xyz| counts as parallel (directional).
PostPerspectiveLight post_perspective_light(const Light& light, const glm::dmat4& world_to_clip,
                                            double parallel_tolerance = 1e-9);

}  // namespace shadow
