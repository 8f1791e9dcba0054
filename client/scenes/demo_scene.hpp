// The built-in procedural scene (`--scene builtin:demo`): a ground plane with a few objects
// standing on it, and a camera, sun and shadow-map biases that show their shadows.
#pragma once

#include "wire/types.hpp"

namespace shadow::scenes {

struct DemoSetup {
  Scene scene;
  Camera camera;                 // suggested view
  Light light;                   // suggested sun
  ShadowMapSettings shadow_map;  // biases that keep lit faces free of acne
};

// Ground: 40 × 40 m at y = 0 (mesh 0, instance 0). Objects: boxes, a sphere, a cylinder and a
// thin pole, all resting on the ground within 8 m of the origin.
DemoSetup demo_scene();

}  // namespace shadow::scenes
