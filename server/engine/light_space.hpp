// Light-space set-up: pure math on a few matrices and bounding boxes, in double precision.
// Every matrix here is world -> texture NDC: after division by w, x and y run 0..1 from the
// image's top-left corner and z (the stored depth) runs 0..1 from near to far.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/types.hpp"

namespace shadow {

struct Bounds {
  glm::dvec3 lo{std::numeric_limits<double>::infinity()};
  glm::dvec3 hi{-std::numeric_limits<double>::infinity()};

  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  void extend(const glm::dvec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void extend(const Bounds& b) {
    if (!b.empty()) extend(b.lo), extend(b.hi);
  }
  std::array<glm::dvec3, 8> corners() const;
};

// The box around `b` after transforming its corners by `m` (with division by w).
Bounds transform_bounds(const Bounds& b, const glm::dmat4& m);
Bounds intersect(const Bounds& a, const Bounds& b);

// Maps GL clip space (x, y, z in [-1, 1], y up) to texture NDC (x, y, z in [0, 1], y down).
glm::dmat4 gl_to_texture_ndc();

struct ViewSetup {
  glm::dmat4 view{1.0};          // world -> eye (camera or light), right-handed, looking down -z
  glm::dmat4 world_to_ndc{1.0};  // world -> texture NDC
  // For a light map: the cube faces (bit k = face k as kernels/prelude.cl's cube_face numbers
  // them) whose camera pixels this map decides; the per-pixel kernels leave the other pixels
  // untouched. 0 = a single map that decides every pixel.
  uint32_t owned_faces = 0;
};

ViewSetup camera_setup(const Camera& camera);

// The camera's pixel rays: from `eye` along ray_00 + u * ray_du + v * ray_dv for texture
// point (u, v), where (0, 0) is the image's top-left corner (w = 0 in the directions).
struct CameraRays {
  glm::vec4 eye, ray_00, ray_du, ray_dv;
};
CameraRays camera_rays(const Camera& camera);

// True unless `b` lies entirely outside one plane of the view's frustum.
bool may_be_visible(const Bounds& world_box, const glm::dmat4& world_to_ndc);

struct InstanceBounds {
  Bounds world;
  bool casts = false;
  bool receives = false;
};

// The uniform shadow-map frustum of a directional light (orthographic) or a spot light (the
// cone's perspective frustum), fitted to the casters that can shadow the receivers in view.
ViewSetup fit_uniform_light(const Light& light, const Camera& camera,
                            const std::vector<InstanceBounds>& instances);

}  // namespace shadow
