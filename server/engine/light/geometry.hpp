// Convex clipping in homogeneous coordinates for the light fits (PSM, cube faces): pure math in
// double precision on a few boxes and planes.
#pragma once

#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "engine/light/light_space.hpp"

namespace shadow {

using Poly = std::vector<glm::dvec4>;

// The world half-spaces of a GL projection * view's frustum (the first `count` planes).
std::vector<glm::dvec4> frustum_planes(const glm::dmat4& world_to_clip, size_t count = 6);

// The part of `in` where dot(plane, v) >= 0 (homogeneous, so it works across w = 0).
Poly clip(const Poly& in, const glm::dvec4& plane);

// Calls f(v) for every vertex of the faces of a hexahedron (corners indexed by bits x, y, z as
// Bounds::corners() orders them) clipped to the half-spaces. Only the surface is clipped: a
// hexahedron around a plane's apex yields no vertex there.
template <typename F>
void for_each_clipped_vertex(const std::array<glm::dvec4, 8>& c,
                             const std::vector<glm::dvec4>& planes, F&& f) {
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  for (const auto& face : kFaces) {
    Poly poly;
    for (int i : face) poly.push_back(c[i]);
    for (const glm::dvec4& p : planes) {
      if (poly.empty()) break;
      poly = clip(poly, p);
    }
    for (const glm::dvec4& v : poly) f(v);
  }
}

template <typename F>
void for_each_clipped_vertex(const Bounds& box, const std::vector<glm::dvec4>& planes, F&& f) {
  if (box.empty()) return;
  std::array<glm::dvec4, 8> c;
  const std::array<glm::dvec3, 8> corners = box.corners();
  for (int i = 0; i < 8; ++i) c[i] = glm::dvec4(corners[i], 1.0);
  for_each_clipped_vertex(c, planes, f);
}

// The six half-spaces of a box.
std::vector<glm::dvec4> box_planes(const Bounds& box);

// A GL projection * view's frustum in the world: its six half-spaces and eight corners (indexed
// by bits x, y, z of NDC -1 / +1, as Bounds::corners()).
struct Frustum {
  explicit Frustum(const glm::dmat4& world_to_clip);
  std::vector<glm::dvec4> planes;
  std::array<glm::dvec4, 8> corners;
};

// Calls f(v) (w = 1) for every vertex of box ∩ frustum ∩ the `extra` half-spaces: the box's
// faces clipped to the frustum and the frustum's faces clipped to the box, so a box that holds
// the whole frustum still yields the frustum's corners. (Vertices on the extra planes' own
// surfaces inside both are not found.)
template <typename F>
void for_each_vertex_in_frustum(const Bounds& box, const Frustum& frustum,
                                const std::vector<glm::dvec4>& extra, F&& f) {
  if (box.empty()) return;
  std::vector<glm::dvec4> planes = frustum.planes;
  planes.insert(planes.end(), extra.begin(), extra.end());
  for_each_clipped_vertex(box, planes, [&](const glm::dvec4& v) { f(v / v.w); });
  planes = box_planes(box);
  planes.insert(planes.end(), extra.begin(), extra.end());
  for_each_clipped_vertex(frustum.corners, planes, [&](const glm::dvec4& v) { f(v / v.w); });
}

// A half-space q . (M p) >= 0 in M's space as a world half-space.
inline glm::dvec4 to_world(const glm::dmat4& m, const glm::dvec4& q) {
  return glm::transpose(m) * q;
}

// Where the light must reach (unit-cube clipping, Kozlov 14.2.1): the vertices of each visible
// receiver's box surface inside the camera's frustum (`world_to_clip`: GL projection * view) and
// the `extra` half-spaces (a spot's cone). Where a box holds the frustum's corners too (terrain
// around the eye) those are left out: they would widen the aim to the whole frustum, measured
// much worse on the forest (PSM misclassified 12% -> 21% beside the walker). A box that holds
// the whole frustum has no surface in it: then the frustum's corners inside it.
std::vector<glm::dvec3> visible_receiver_points(const glm::dmat4& world_to_clip,
                                                const std::vector<InstanceBounds>& instances,
                                                const std::vector<glm::dvec4>& extra = {});

// The GL frustum planes (x, y, z in [-w, w]) of clip space: left, right, bottom, top, near, far.
inline constexpr std::array<glm::dvec4, 6> kClipFrustum = {
    glm::dvec4{1, 0, 0, 1},  glm::dvec4{-1, 0, 0, 1}, glm::dvec4{0, 1, 0, 1},
    glm::dvec4{0, -1, 0, 1}, glm::dvec4{0, 0, 1, 1},  glm::dvec4{0, 0, -1, 1}};

}  // namespace shadow
