#include "engine/light/geometry.hpp"

namespace shadow {

Poly clip(const Poly& in, const glm::dvec4& plane) {
  Poly out;
  for (size_t k = 0; k < in.size(); ++k) {
    const glm::dvec4 &a = in[k], &b = in[(k + 1) % in.size()];
    const double da = glm::dot(plane, a), db = glm::dot(plane, b);
    if (da >= 0) out.push_back(a);
    if ((da >= 0) != (db >= 0)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

std::vector<glm::dvec4> box_planes(const Bounds& box) {
  return {{1, 0, 0, -box.lo.x}, {-1, 0, 0, box.hi.x}, {0, 1, 0, -box.lo.y},
          {0, -1, 0, box.hi.y}, {0, 0, 1, -box.lo.z}, {0, 0, -1, box.hi.z}};
}

std::vector<glm::dvec4> frustum_planes(const glm::dmat4& world_to_clip, size_t count) {
  std::vector<glm::dvec4> planes;
  for (size_t i = 0; i < count && i < kClipFrustum.size(); ++i)
    planes.push_back(to_world(world_to_clip, kClipFrustum[i]));
  return planes;
}

Frustum::Frustum(const glm::dmat4& world_to_clip) : planes(frustum_planes(world_to_clip)) {
  const glm::dmat4 inv = glm::inverse(world_to_clip);
  for (int i = 0; i < 8; ++i) {
    const glm::dvec4 v = inv * glm::dvec4((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1, 1);
    corners[i] = v / v.w;
  }
}

std::vector<glm::dvec3> visible_receiver_points(const glm::dmat4& world_to_clip,
                                                const std::vector<InstanceBounds>& instances,
                                                const std::vector<glm::dvec4>& extra) {
  const glm::dmat4 cam_tex = gl_to_texture_ndc() * world_to_clip;
  const Frustum view_frustum(world_to_clip);
  std::vector<glm::dvec4> in_view = view_frustum.planes;
  in_view.insert(in_view.end(), extra.begin(), extra.end());
  std::vector<glm::dvec3> points;
  for (const InstanceBounds& ib : instances) {
    if (!ib.receives || !may_be_visible(ib.world, cam_tex)) continue;
    const size_t before = points.size();
    for_each_clipped_vertex(ib.world, in_view,
                            [&](const glm::dvec4& v) { points.push_back(glm::dvec3(v)); });
    if (points.size() == before)
      for_each_vertex_in_frustum(ib.world, view_frustum, extra,
                                 [&](const glm::dvec4& v) { points.push_back(glm::dvec3(v)); });
  }
  return points;
}

}  // namespace shadow
