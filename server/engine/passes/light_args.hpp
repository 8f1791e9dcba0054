// The light as the per-pixel kernels take it (shadow_test, pcf, pcss, blur): four arguments in
// the order kind, position, axis, cos_half_cone. Kinds match LIGHT_* in kernels/prelude.cl.
#pragma once

#include <cmath>
#include <string>

#include <glm/glm.hpp>

#include "engine/device_types.hpp"
#include "engine/light_space.hpp"
#include "engine/types.hpp"

namespace shadow {

struct LightArgs {
  int kind;             // LIGHT_DIRECTIONAL 0, LIGHT_SPOT 1, LIGHT_POINT 2
  glm::vec4 position;   // spot: apex; point: the light
  glm::vec4 axis;       // unit direction of travel (directional) or cone axis (spot)
  float cos_half_cone;  // spot: outside the cone nothing is lit
};

inline LightArgs light_args(const Light& light) {
  const int kind = light.type == LightType::kSpot ? 1 : light.type == LightType::kPoint ? 2 : 0;
  // A point light has no axis; any unit vector keeps the kernels' cone arithmetic finite.
  const glm::vec3 axis =
      light.type == LightType::kPoint ? glm::vec3(0, -1, 0) : glm::normalize(light.direction);
  return {kind, glm::vec4(light.position, 1.0f), glm::vec4(axis, 0.0f),
          std::cos(glm::radians(0.5f * light.cone_angle_deg))};
}

// The program variant for a map: cube faces compile the per-pixel face check in (CUBE_FACES);
// a single map, which decides every pixel, goes without it.
inline std::string faces_option(const ViewSetup& light_view) {
  return light_view.faces.owned != 0 ? "-DCUBE_FACES" : "";
}

// The faces_t argument: which pixels a map decides.
inline FacesItem faces_args(const CubeFaces& f) {
  FacesItem item{};
  item.space = glm::mat4(f.space);
  item.origin = glm::vec4(glm::vec3(f.origin), 1.0f);
  item.inv_pos = glm::vec4(glm::vec3(f.inv_pos), 0.0f);
  item.inv_neg = glm::vec4(glm::vec3(f.inv_neg), 0.0f);
  item.owned = f.owned;
  return item;
}

}  // namespace shadow
