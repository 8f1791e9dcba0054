#include "test_scene.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include "wire/convert.hpp"

namespace shadow::test {

std::shared_ptr<Scene> ground_and_box() {
  auto scene = std::make_shared<Scene>();
  Mesh ground;
  ground.positions = {-10, 0, -10, 10, 0, -10, 10, 0, 10, -10, 0, 10};
  ground.indices = {0, 3, 2, 0, 2, 1};  // counter-clockwise seen from +Y
  scene->meshes.push_back(ground);

  // Unit cube centred on the origin, outward counter-clockwise faces.
  Mesh box;
  box.positions = {-.5f, -.5f, -.5f, .5f, -.5f, -.5f, .5f, .5f, -.5f, -.5f, .5f, -.5f,
                   -.5f, -.5f, .5f,  .5f, -.5f, .5f,  .5f, .5f, .5f,  -.5f, .5f, .5f};
  box.indices = {0, 3, 2, 0, 2, 1,   // -z
                 4, 5, 6, 4, 6, 7,   // +z
                 0, 4, 7, 0, 7, 3,   // -x
                 1, 2, 6, 1, 6, 5,   // +x
                 0, 1, 5, 0, 5, 4,   // -y
                 3, 7, 6, 3, 6, 2};  // +y
  scene->meshes.push_back(box);

  scene->instances.push_back({0, glm::mat4(1.0f), true, true});
  scene->instances.push_back(
      {1, glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.5f, 0.0f)), true, true});
  return scene;
}

RenderRequest small_request(std::vector<Product> products) {
  RenderRequest request;
  request.scene = ground_and_box();
  request.camera.eye = {0.0f, 6.0f, 12.0f};
  request.camera.target = {0.0f, 0.0f, 0.0f};
  request.camera.up = {0.0f, 1.0f, 0.0f};
  request.camera.fov_deg = 60.0f;
  request.camera.width = 320;
  request.camera.height = 240;
  request.camera.near = 0.1f;
  request.camera.far = 100.0f;
  request.lights[0].type = LightType::kDirectional;
  request.lights[0].direction = {0.3f, -1.0f, 0.2f};
  request.shadow_map.size = 512;
  request.shadow_map.bias_constant = 0.001f;
  request.shadow_map.bias_slope = 1.0f;
  request.products = std::move(products);
  return request;
}

v1::RenderRequest tiny_proto_request() {
  RenderRequest request = small_request();
  request.camera.width = 64;
  request.camera.height = 48;
  request.shadow_map.size = 256;
  return convert::to_proto(request);
}

}  // namespace shadow::test
