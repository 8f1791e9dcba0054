// The engine tests' scene: a 20 x 20 m ground with a 2 x 2 m square occluder 2 m above it under a
// sun straight down, whose shadow has a closed form, rendered by the shared engine
// (common/engine_fixture.hpp).
#pragma once

#include <string>

#include "engine/engine.hpp"
#include "engine_fixture.hpp"
#include "wire/errors.hpp"

namespace shadow::testing {

// A horizontal square of half-size `half` at height `y`, facing up.
inline Mesh quad(float half, float y) {
  return Mesh{
      {-half, y, -half, half, y, -half, half, y, half, -half, y, half}, {0, 2, 1, 0, 3, 2}, {}, {}};
}

// The field the shared engine refuses `r` for, "exhausted: <field>" for a limit, or "(accepted)".
inline std::string refused_field(const RenderRequest& r) {
  try {
    engine().render(r);
  } catch (const InvalidArgument& e) {
    return e.field();
  } catch (const ResourceExhausted& e) {
    return "exhausted: " + e.field();
  }
  return "(accepted)";
}

inline RenderRequest occluder_request() {
  auto scene = std::make_shared<Scene>();
  scene->meshes = {quad(10, 0), quad(1, 2)};
  scene->instances = {Instance{0}, Instance{1}};
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 12, 6};
  r.camera.target = {0, 0, 0};
  r.camera.width = 320;
  r.camera.height = 240;
  r.camera.near = 0.5f;
  r.camera.far = 100.0f;
  r.lights[0].direction = {0, -1, 0};
  r.shadow_map.size = 1024;
  r.shadow_map.bias_constant = 1e-4f;
  r.products = {Product::kVisibility, Product::kPosition};
  return r;
}

}  // namespace shadow::testing
