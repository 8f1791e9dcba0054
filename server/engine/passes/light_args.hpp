// The light and the shadow-map lookup as kernels take them (light_t and shadow_lookup_t in
// kernels/prelude.cl, mirrored by LightItem and ShadowLookupItem in engine/device_types.hpp),
// and the cube-face ownership (faces_t) of the per-pixel kernels.
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "engine/device_types.hpp"
#include "engine/light/light_space.hpp"
#include "wire/types.hpp"

namespace shadow {

// light_t: the per-pixel kernels' spot cone and the rasterizer's world-space bias direction.
inline LightItem light_item(const Light& light) {
  LightItem item{};
  item.kind = light.type == LightType::kSpot    ? kLightSpot
              : light.type == LightType::kPoint ? kLightPoint
                                                : kLightDirectional;
  item.position = glm::vec4(light.position, 1.0f);
  // A point light has no axis; any unit vector keeps the kernels' cone arithmetic finite.
  // Normalized in double: a tiny direction's float length underflows, and the kernels' sign of
  // n . axis must not depend on the direction's scale.
  item.axis = glm::vec4(light.type == LightType::kPoint
                            ? glm::vec3(0, -1, 0)
                            : glm::vec3(glm::normalize(glm::dvec3(light.direction))),
                        0.0f);
  item.cos_half_cone = std::cos(glm::radians(0.5f * light.cone_angle_deg));
  // As the area-light reference (oracle/area_light.hpp) and PCSS read Light::size.
  item.disk = light.type == LightType::kDirectional
                  ? float(std::tan(glm::radians(0.5 * double{light.size})))
                  : light.size;
  return item;
}

// shadow_lookup_t: a camera point taken into `light_view`'s map of map_size^2 texels and compared
// there with the NDC-depth bias (blur_visibility reads a prefiltered map and no bias).
inline ShadowLookupItem shadow_lookup(const ViewSetup& light_view, const Light& light,
                                      uint32_t map_size, float bias_constant = 0.0f,
                                      float bias_slope = 0.0f) {
  ShadowLookupItem item{};
  item.to_ndc = glm::mat4(light_view.world_to_ndc);
  item.light = light_item(light);
  item.map_size = map_size;
  item.bias_constant = bias_constant;
  item.bias_slope = bias_slope;
  return item;
}
inline ShadowLookupItem shadow_lookup(const ViewSetup& light_view, const Light& light,
                                      const ShadowMapSettings& settings) {
  return shadow_lookup(light_view, light, settings.size, settings.bias_constant,
                       settings.bias_slope);
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
