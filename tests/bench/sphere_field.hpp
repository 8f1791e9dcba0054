// What shadow-atlas-bench and shadow-csm-images share: the scene of twelve spheres floating
// 0.3-3 m over a 24 m ground (all receiving, all with their own UVs) under a 3-degree sun, and
// the raw image files scripts/plot_atlas.py and scripts/plot_csm_images.py read.
#pragma once

#include <fstream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "scenes/shapes.hpp"
#include "wire/types.hpp"

namespace shadow::bench {

inline RenderRequest sphere_field(uint32_t width, uint32_t height, uint32_t map, uint32_t tile) {
  auto scene = std::make_shared<Scene>();
  scene->meshes = {scenes::make_grid(24.0f, 8), scenes::make_sphere(32, 16)};
  scene->instances = {Instance{0}};
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 12; ++i) {
    const float r = 0.4f + 0.6f * u(rng), h = r + 0.3f + 2.7f * u(rng);
    Instance s{1};
    s.transform =
        glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(16 * u(rng) - 8, h, 16 * u(rng) - 8)),
                   glm::vec3(r));
    scene->instances.push_back(s);
  }
  RenderRequest req;
  req.scene = scene;
  req.camera.eye = {0, 10, 16};
  req.camera.target = {0, 0, 0};
  req.camera.width = width, req.camera.height = height;
  req.camera.near = 0.5f, req.camera.far = 100;
  req.lights[0].direction = glm::normalize(glm::vec3(0.4f, -1.0f, 0.3f));
  req.lights[0].size = 3.0f;
  req.shadow_map.size = map;
  req.shadow_map.fit = MapFit::kScene;
  req.atlas.tile = tile;
  req.products = {Product::kVisibility};
  return req;
}

// Raw little-endian float32 rows (scripts/plot_atlas.py reads them).
inline void write_floats(const std::string& dir, const std::string& name,
                         const std::vector<float>& v) {
  std::ofstream out(dir + "/" + name + ".f32", std::ios::binary);
  out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(float)));
  if (!out) throw std::runtime_error("cannot write " + dir + "/" + name + ".f32");
}

}  // namespace shadow::bench
