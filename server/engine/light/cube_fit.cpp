#include "engine/light/cube_fit.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/geometry.hpp"

namespace shadow {
namespace {

const glm::dvec3 kAxes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
const glm::dvec3 kUps[6] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};

}  // namespace

glm::dvec3 cube_face_axis(int k) {
  return kAxes[k];
}
glm::dvec3 cube_face_up(int k) {
  return kUps[k];
}

int cube_face(const glm::dvec3& d) {
  return face_of(CubeFaces{}, d);
}

CubeFit fit_cube(const Light& light, const Camera& camera,
                 const std::vector<InstanceBounds>& instances, uint32_t map_size, uint32_t guard,
                 double min_caster_distance, MapFit map_fit) {
  const glm::dvec3 p(light.position);
  // The 90-degree core spans texels [guard, size - guard]: half-extent h in tangent units.
  const double h = double(map_size) / (double(map_size) - 2.0 * guard);
  const Frustum view(glm::inverse(gl_to_texture_ndc()) * camera_setup(camera).world_to_ndc);
  // Every caster point x in a face has depth >= |x - p| / sqrt(1 + 2 h^2).
  const double near_bound = 0.999 * min_caster_distance / std::sqrt(1.0 + 2.0 * h * h);

  CubeFit fit;
  for (int k = 0; k < 6; ++k) {
    CubeFaceFit& face = fit.faces[k];
    const glm::dvec3 axis = kAxes[k];
    face.setup.view = glm::lookAt(p, p + axis, kUps[k]);
    face.setup.faces.origin = p;
    face.setup.faces.owned = 1u << k;
    face.setup.world_to_ndc = glm::dmat4(0.0);  // an empty map: every point is off it (lit)
    const std::vector<glm::dvec4> sides =
        frustum_planes(glm::frustum(-h, h, -h, h, 1.0, 2.0) * face.setup.view, 4);
    auto depth = [&](const glm::dvec4& v) { return glm::dot(axis, glm::dvec3(v) / v.w - p); };

    double far = -INFINITY;
    int receivers = 0;
    for (const InstanceBounds& ib : instances) {
      if (!ib.receives) continue;
      bool seen = false;
      const auto reach = [&](const glm::dvec4& v) { far = std::max(far, depth(v)), seen = true; };
      if (map_fit == MapFit::kScene)
        for_each_clipped_vertex(ib.world, sides, [&](const glm::dvec4& v) { reach(v / v.w); });
      else
        for_each_vertex_in_frustum(ib.world, view, sides, reach);
      receivers += seen;
    }
    const char* which = map_fit == MapFit::kScene ? "" : "visible ";
    if (receivers == 0) {
      face.reason = std::string("no ") + which + "receiver";
      continue;
    }
    std::vector<glm::dvec4> caster_planes = sides;
    caster_planes.push_back(glm::dvec4(-axis, far + glm::dot(axis, p)));  // depth <= far
    double near = INFINITY;
    int casters = 0;
    for (const InstanceBounds& ib : instances) {
      if (!ib.casts) continue;
      // A box around the light may hold geometry anywhere in the face, at any depth.
      bool seen = ib.world.contains(p);
      if (seen) near = 0.0;
      for_each_clipped_vertex(ib.world, caster_planes, [&](const glm::dvec4& v) {
        near = std::min(near, depth(v)), seen = true;
      });
      casters += seen;
    }
    if (casters == 0) {
      face.reason = "no caster between the light and the " + std::to_string(receivers) + " " +
                    which + "receiver(s)";
      continue;
    }
    far = 1.001 * std::max(far, 1e-6);
    near = std::clamp(std::max(0.999 * near, near_bound), 1e-4 * far, 0.5 * far);
    face.rendered = true;
    face.reason = std::to_string(casters) + " caster(s) in front of " + std::to_string(receivers) +
                  " " + which + "receiver(s)";
    face.near = near, face.far = far;
    face.setup.depth = {MapDepth::kPerspective, near, far};
    face.setup.world_to_ndc = gl_to_texture_ndc() *
                              glm::frustum(-h * near, h * near, -h * near, h * near, near, far) *
                              face.setup.view;
  }
  return fit;
}

}  // namespace shadow
