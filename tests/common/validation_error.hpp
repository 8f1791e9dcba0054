// What the engine's validation tests share: a smallest valid request and the message a request
// is refused with.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "engine/plan/validate.hpp"
#include "wire/errors.hpp"

namespace shadow {

// One triangle, one instance, the shadow map only: accepted as it is.
inline RenderRequest one_triangle_request() {
  RenderRequest r;
  auto scene = std::make_shared<Scene>();
  scene->meshes.push_back(Mesh{{0, 0, 0, 1, 0, 0, 0, 0, 1}, {0, 1, 2}, {}, {}});
  scene->instances.push_back(Instance{});
  r.scene = scene;
  r.products = {Product::kShadowMap};
  return r;
}

// The InvalidArgument's message, or "(accepted)".
inline std::string validation_error(const RenderRequest& r) {
  try {
    validate(r, {UINT64_MAX, UINT64_MAX});
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "(accepted)";
}

}  // namespace shadow
