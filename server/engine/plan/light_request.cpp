#include "engine/plan/light_request.hpp"

#include <algorithm>

namespace shadow {

Technique resolved_technique(Technique technique, LightType light) {
  if (technique != Technique::kDefault) return technique;
  return light == LightType::kPoint ? Technique::kCube : Technique::kUniform;
}

RenderRequest for_light(const RenderRequest& request, size_t i) {
  RenderRequest one = request;
  one.lights = {request.lights.at(i)};
  one.shadow_map.technique = resolved_technique(request.shadow_map.technique, one.lights[0].type);
  return one;
}

bool per_light(Product product) {
  return product != Product::kPosition && product != Product::kAtlasUvs;
}

bool needs_light(const RenderRequest& request) {
  return std::any_of(request.products.begin(), request.products.end(), per_light);
}

std::string light_field(size_t i) {
  return "lights[" + std::to_string(i) + "]";
}

std::string light_texture_suffix(const RenderRequest& request, size_t i) {
  return request.lights.size() > 1 ? "_light" + std::to_string(i) : "";
}

std::string light_pass_prefix(const RenderRequest& request, size_t i) {
  return request.lights.size() > 1 ? "light" + std::to_string(i) + "." : "";
}

}  // namespace shadow
