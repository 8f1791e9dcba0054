// Light-space set-up: pure math on a few matrices and bounding boxes, in double precision.
// Every matrix here is world -> texture NDC: after division by w, x and y run 0..1 from the
// image's top-left corner and z (the stored depth) runs 0..1 from near to far.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "wire/types.hpp"

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
  bool contains(const glm::dvec3& p) const {
    return glm::all(glm::greaterThanEqual(p, lo)) && glm::all(glm::lessThanEqual(p, hi));
  }
  std::array<glm::dvec3, 8> corners() const;
};

// The box around `b` after transforming its corners by `m` (with division by w).
Bounds transform_bounds(const Bounds& b, const glm::dmat4& m);
Bounds intersect(const Bounds& a, const Bounds& b);

// Maps GL clip space (x, y, z in [-1, 1], y up) to texture NDC (x, y, z in [0, 1], y down).
glm::dmat4 gl_to_texture_ndc();

// How the maps of a cube share the camera's pixels: a pixel at world x belongs to the face
// through which the line from `origin` through x leaves the cube, in `space` (homogeneous,
// divided by w): the largest of (x - origin)_i * inv_pos_i and -(x - origin)_i * inv_neg_i over
// the axes i, ties to the earlier face in +x -x +y -y +z -z order (Kozlov 14.2.2, listing
// 14-1). For a point light's cube: space = the world, origin = the light, all inverse
// distances 1 (the major axis). `owned` = the faces a map decides (bit k = face k); 0 = a single
// map that decides every pixel. The per-pixel kernels leave other pixels untouched.
struct CubeFaces {
  glm::dmat4 space{1.0};
  glm::dvec3 origin{0.0};
  glm::dvec3 inv_pos{1.0}, inv_neg{1.0};
  uint32_t owned = 0;
};

// The face (0..5) that owns world point x, as the kernels decide it.
int face_of(const CubeFaces& faces, const glm::dvec3& x);

// A map's depth along its own axis, between `near` and `far` there: z = (d - near) / (far -
// near) for an orthographic projection in world units (uniform directional maps), z = alpha +
// beta / d for a perspective one (spot maps, cube faces, PSM's point light in post-perspective
// space). kStored: z is only monotone with distance (PSM's orthographic and inverted maps,
// LiSPSM), and lookups that want linear depth (CSM) take it as stored.
struct MapDepth {
  enum Kind { kStored, kOrthographic, kPerspective } kind = kStored;
  double near = 0, far = 0;
  bool operator==(const MapDepth&) const = default;
};

struct ViewSetup {
  glm::dmat4 view{1.0};          // world -> eye (camera or light), right-handed, looking down -z
  glm::dmat4 world_to_ndc{1.0};  // world -> texture NDC
  CubeFaces faces;               // for one face of a cube: the camera pixels this map decides
  MapDepth depth;                // a light map's
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
// cone's perspective frustum), fitted to the casters that can shadow the receivers in view
// (kView) or all receivers (kScene: the camera is not read).
ViewSetup fit_uniform_light(const Light& light, const Camera& camera,
                            const std::vector<InstanceBounds>& instances,
                            MapFit fit = MapFit::kView);

}  // namespace shadow
