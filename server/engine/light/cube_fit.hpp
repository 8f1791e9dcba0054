// Omnidirectional point-light shadows: six 90-degree perspective faces around the light, the
// cube-face projection of Kozlov 14.2.2 for a point light in world space. Pure math, double
// precision.
//
// Face k looks from the light along its axis (+x, -x, +y, -y, +z, -z) with the up vectors of
// the OpenGL cube-map convention (-y for the x and z faces, +z for +y, -z for -y); row 0 of a
// face's texture is its top. A camera pixel belongs to the face of the major axis of
// (position - light), ties to the earlier face (cube_face below; CubeFaces in light_space.hpp,
// decided the same way by the kernels), so every pixel has exactly one face and the lookup is
// continuous across seams. Each face's frustum is
// widened by a guard band of `guard` texels on every side: the 90-degree core maps to texels
// [guard, size - guard], so a filter reaching `guard` texels around a point in its own face
// never leaves the face's texture.
//
// A face is rendered only if it can hold a caster of a visible receiver: a visible receiver
// (its box clipped to the camera's frustum) lies in the face's frustum, and a caster box lies
// in that frustum no farther from the light than the farthest such receiver.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "engine/light/light_space.hpp"
#include "wire/types.hpp"

namespace shadow {

inline constexpr const char* kCubeFaceNames[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};

// The widest guard band a face of `map_size` texels takes: an eighth of it.
inline uint32_t max_guard(uint32_t map_size) {
  return map_size / 8;
}

struct CubeFaceFit {
  bool rendered = false;
  std::string reason;        // why it is rendered or skipped
  ViewSetup setup;           // faces.owned = 1 << k; world_to_ndc is all zeros when not rendered
  double near = 0, far = 0;  // along the face's axis
};

struct CubeFit {
  std::array<CubeFaceFit, 6> faces;
};

// `min_caster_distance`: a lower bound of the distance from the light to every caster triangle
// (measured on the device, see passes/light_distance); it bounds each face's near plane where a
// caster's box holds the light. Casters nearer to the light than 1e-4 of a face's far distance
// are clipped (the depth range would be useless). `fit`: the receivers the faces serve, those in
// the camera's view (kView) or all of them (kScene: the camera is not read).
CubeFit fit_cube(const Light& light, const Camera& camera,
                 const std::vector<InstanceBounds>& instances, uint32_t map_size, uint32_t guard,
                 double min_caster_distance, MapFit fit = MapFit::kView);

// Face k's outward axis and its up vector (the OpenGL cube-map convention).
glm::dvec3 cube_face_axis(int k);
glm::dvec3 cube_face_up(int k);

// The face of direction d from the light: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z.
int cube_face(const glm::dvec3& d);

}  // namespace shadow
