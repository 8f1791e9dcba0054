#include "engine/geometry.hpp"

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

}  // namespace shadow
