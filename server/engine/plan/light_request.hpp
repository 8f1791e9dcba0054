// A request's lights one at a time. The engine's per-light code (validation, the plan's light
// steps, the fit, the maps, visibility) takes a request narrowed to one light, whose `lights`
// holds just that light and whose technique has its default resolved for it; the camera view
// is shared by all of them.
#pragma once

#include <cstddef>
#include <string>

#include "wire/types.hpp"

namespace shadow {

// Lights per request: each costs its own maps, so the list is bounded like any other size.
constexpr size_t kMaxLights = 16;

// kDefault -> kCube for a point light, kUniform otherwise; every other technique as it is.
Technique resolved_technique(Technique technique, LightType light);

// `request` with only lights[i], its technique resolved.
RenderRequest for_light(const RenderRequest& request, size_t i);
// The light of a request narrowed by for_light.
inline const Light& only_light(const RenderRequest& one) {
  return one.lights.front();
}

// Products computed once per light (all but POSITION, the camera's alone, and ATLAS_UVS, the
// scene's).
bool per_light(Product product);
bool needs_light(const RenderRequest& request);

// The field path of lights[i] ("lights[2]"), and the suffix of its textures and the prefix of
// its passes when the request has several lights ("_light2", "light2."; empty for one light).
std::string light_field(size_t i);
std::string light_texture_suffix(const RenderRequest& request, size_t i);
std::string light_pass_prefix(const RenderRequest& request, size_t i);

}  // namespace shadow
