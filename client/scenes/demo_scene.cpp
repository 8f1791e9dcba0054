#include "scenes/demo_scene.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include "scenes/shapes.hpp"

namespace shadow::scenes {
namespace {

// Places `mesh` scaled by `size` with its base (object-space y = `base`) on the ground at `at`.
Instance place(uint32_t mesh, glm::vec3 at, glm::vec3 size, float base, float yaw_deg = 0) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), at);
  m = glm::rotate(m, glm::radians(yaw_deg), glm::vec3(0, 1, 0));
  m = glm::scale(m, size);
  m = glm::translate(m, glm::vec3(0, -base, 0));
  Instance instance;
  instance.mesh = mesh;
  instance.transform = m;
  return instance;
}

}  // namespace

DemoSetup demo_scene() {
  DemoSetup demo;
  Scene& s = demo.scene;
  s.meshes = {make_grid(40.0f, 8), make_box(), make_sphere(48, 24), make_cylinder(32)};
  enum : uint32_t { kGround, kBox, kSphere, kCylinder };

  Instance ground;
  ground.mesh = kGround;
  ground.casts_shadows = false;  // nothing lies below it
  s.instances.push_back(ground);
  s.instances.push_back(place(kBox, {-4, 0, 0}, {2, 2, 2}, -0.5f, 30));
  s.instances.push_back(place(kBox, {2.5f, 0, -4.5f}, {1.5f, 4, 1.5f}, -0.5f, -15));
  s.instances.push_back(place(kBox, {-1, 0, -7}, {5, 0.6f, 1}, -0.5f));
  s.instances.push_back(place(kSphere, {3.5f, 0, 2.5f}, {1.5f, 1.5f, 1.5f}, -1));
  s.instances.push_back(place(kCylinder, {-3.5f, 0, 5}, {0.8f, 3, 0.8f}, 0));
  s.instances.push_back(place(kCylinder, {0.5f, 0, 1.5f}, {0.08f, 6, 0.08f}, 0));  // thin pole

  demo.camera.eye = {13, 9, 15};
  demo.camera.target = {0, 1, 0};
  demo.camera.up = {0, 1, 0};
  demo.camera.fov_deg = 50;
  demo.camera.width = 1280;
  demo.camera.height = 720;
  demo.camera.near = 0.5f;
  demo.camera.far = 200;

  // Afternoon sun from behind-left of the camera, so shadows fall to the right of the objects.
  demo.light.type = LightType::kDirectional;
  demo.light.direction = glm::normalize(glm::vec3(0.9f, -1.0f, -0.3f));
  demo.light.size = 0.53f;  // the sun's angular diameter in degrees
  // demo.shadow_map keeps the server's default bias (constant 2e-5, slope 0.75).
  return demo;
}

}  // namespace shadow::scenes
