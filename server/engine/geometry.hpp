// Convex clipping in homogeneous coordinates for the light fits (PSM, cube faces): pure math in
// double precision on a few boxes and planes.
#pragma once

#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "engine/light_space.hpp"

namespace shadow {

using Poly = std::vector<glm::dvec4>;

// The part of `in` where dot(plane, v) >= 0 (homogeneous, so it works across w = 0).
Poly clip(const Poly& in, const glm::dvec4& plane);

// Calls f(v) for every vertex of `box`'s faces (as polygons) clipped to the world half-spaces.
// Only the box's surface is clipped: a box around a plane's apex yields no vertex there.
template <typename F>
void for_each_clipped_vertex(const Bounds& box, const std::vector<glm::dvec4>& planes, F&& f) {
  if (box.empty()) return;
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  const std::array<glm::dvec3, 8> c = box.corners();
  for (const auto& face : kFaces) {
    Poly poly;
    for (int i : face) poly.emplace_back(c[i], 1.0);
    for (const glm::dvec4& p : planes) {
      if (poly.empty()) break;
      poly = clip(poly, p);
    }
    for (const glm::dvec4& v : poly) f(v);
  }
}

// A half-space q . (M p) >= 0 in M's space as a world half-space.
inline glm::dvec4 to_world(const glm::dmat4& m, const glm::dvec4& q) {
  return glm::transpose(m) * q;
}

// The GL frustum planes (x, y, z in [-w, w]) of clip space: left, right, bottom, top, near, far.
inline constexpr std::array<glm::dvec4, 6> kClipFrustum = {
    glm::dvec4{1, 0, 0, 1},  glm::dvec4{-1, 0, 0, 1}, glm::dvec4{0, 1, 0, 1},
    glm::dvec4{0, -1, 0, 1}, glm::dvec4{0, 0, 1, 1},  glm::dvec4{0, 0, -1, 1}};

// The world half-spaces of a GL projection * view's frustum (the first `count` planes).
std::vector<glm::dvec4> frustum_planes(const glm::dmat4& world_to_clip, size_t count = 6);

}  // namespace shadow
