#include "oracle/scenes.hpp"

#include <cmath>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

namespace shadow::scenes {
namespace {

uint32_t vertex(Mesh& m, glm::vec3 p) {
  m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
  return static_cast<uint32_t>(m.vertex_count() - 1);
}

// Appends triangle (a, b, c) wound so that its normal points along `outward`.
void triangle(Mesh& m, uint32_t a, uint32_t b, uint32_t c, glm::vec3 outward) {
  auto at = [&](uint32_t i) {
    return glm::vec3(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]);
  };
  if (glm::dot(glm::cross(at(b) - at(a), at(c) - at(a)), outward) < 0.0f) std::swap(b, c);
  m.indices.insert(m.indices.end(), {a, b, c});
}

void quad(Mesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t d, glm::vec3 outward) {
  triangle(m, a, b, c, outward);
  triangle(m, a, c, d, outward);
}

}  // namespace

Mesh box_mesh() {
  Mesh m;
  for (int i = 0; i < 8; ++i) {
    vertex(m, {i & 1 ? 0.5f : -0.5f, i & 2 ? 0.5f : -0.5f, i & 4 ? 0.5f : -0.5f});
  }
  // Each face: the four corners with one coordinate bit fixed, in cyclic order.
  for (int axis = 0; axis < 3; ++axis) {
    const int u = 1 << ((axis + 1) % 3), v = 1 << ((axis + 2) % 3);
    for (int side = 0; side < 2; ++side) {
      const uint32_t base = side ? (1u << axis) : 0u;
      glm::vec3 out(0.0f);
      out[axis] = side ? 1.0f : -1.0f;
      quad(m, base, base | u, base | u | v, base | v, out);
    }
  }
  return m;
}

Mesh grid_mesh(uint32_t n) {
  Mesh m;
  for (uint32_t j = 0; j <= n; ++j) {
    for (uint32_t i = 0; i <= n; ++i) {
      vertex(m, {static_cast<float>(i) / n - 0.5f, 0.0f, static_cast<float>(j) / n - 0.5f});
    }
  }
  for (uint32_t j = 0; j < n; ++j) {
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i;
      quad(m, a, a + 1, a + n + 2, a + n + 1, {0, 1, 0});
    }
  }
  return m;
}

Mesh prism_mesh(uint32_t sides) {
  Mesh m;
  const uint32_t bottom = vertex(m, {0, 0, 0}), top = vertex(m, {0, 1, 0});
  const uint32_t ring = static_cast<uint32_t>(m.vertex_count());
  for (uint32_t k = 0; k < sides; ++k) {
    const float a = 2.0f * static_cast<float>(M_PI) * k / sides;
    vertex(m, {0.5f * std::cos(a), 0.0f, 0.5f * std::sin(a)});
    vertex(m, {0.5f * std::cos(a), 1.0f, 0.5f * std::sin(a)});
  }
  for (uint32_t k = 0; k < sides; ++k) {
    const uint32_t b0 = ring + 2 * k, b1 = ring + 2 * ((k + 1) % sides);
    const float a = 2.0f * static_cast<float>(M_PI) * (k + 0.5f) / sides;
    quad(m, b0, b1, b1 + 1, b0 + 1, {std::cos(a), 0.0f, std::sin(a)});
    triangle(m, bottom, b0, b1, {0, -1, 0});
    triangle(m, top, b0 + 1, b1 + 1, {0, 1, 0});
  }
  return m;
}

glm::mat4 trs(glm::vec3 translate, float angle_deg, glm::vec3 axis, glm::vec3 scale) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), translate);
  m = glm::rotate(m, glm::radians(angle_deg), axis);
  return glm::scale(m, scale);
}

uint32_t add(Scene& scene, Mesh mesh, const glm::mat4& transform, bool casts, bool receives) {
  scene.meshes.push_back(std::move(mesh));
  Instance inst;
  inst.mesh = static_cast<uint32_t>(scene.meshes.size() - 1);
  inst.transform = transform;
  inst.casts_shadows = casts;
  inst.receives_shadows = receives;
  scene.instances.push_back(inst);
  return static_cast<uint32_t>(scene.instances.size() - 1);
}

Setup test_scene() {
  Setup s;
  Scene& sc = s.scene;
  add(sc, grid_mesh(8), trs({0, 0, 0}, 0, {0, 1, 0}, {40, 1, 40}));
  add(sc, box_mesh(), trs({-5, 1, -3}, 0, {0, 1, 0}, {2, 2, 2}));            // resting cube
  add(sc, box_mesh(), trs({4, 1.5f, 2}, 30, {0, 1, 0}, {1, 3, 1}));          // rotated column
  add(sc, box_mesh(), trs({0, 2.5f, 5}, 0, {0, 1, 0}, {1.5f, 0.5f, 1.5f}));  // floating
  for (glm::vec3 p : {glm::vec3(-8, 0, 6), glm::vec3(-2, 0, -8), glm::vec3(7, 0, -5),
                      glm::vec3(9, 0, 8), glm::vec3(2, 0, -1)}) {
    add(sc, prism_mesh(8), trs(p, 0, {0, 1, 0}, {0.12f, 4, 0.12f}));  // thin poles
  }
  add(sc, box_mesh(), trs({-9, 2, -4}, 25, {0, 0, 1}, {4, 0.15f, 2.5f}));  // tilted slab
  add(sc, box_mesh(), trs({-11, 0.5f, 9}, 0, {0, 1, 0}, {1, 1, 1}), /*casts=*/false);
  add(sc, box_mesh(), trs({11, 0.75f, -9}, 15, {0, 1, 0}, {1.5f, 1.5f, 1.5f}), true,
      /*receives=*/false);

  s.light.type = LightType::kDirectional;
  s.light.direction = glm::normalize(glm::vec3(-0.7f, -1.0f, -0.4f));
  s.camera.eye = {0, 18, 26};
  s.camera.target = {0, 0, 0};
  s.camera.fov_deg = 60;
  s.camera.width = 1280;
  s.camera.height = 720;
  s.camera.near = 0.1f;
  s.camera.far = 200.0f;
  return s;
}

Setup random_triangles(size_t count, float extent, float edge, uint32_t seed) {
  Setup s;
  add(s.scene, grid_mesh(1), trs({0, 0, 0}, 0, {0, 1, 0}, {extent, 1, extent}));
  Mesh m;
  m.positions.reserve(9 * count);
  m.indices.reserve(3 * count);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-0.45f * extent, 0.45f * extent), height(0.5f, 3.0f),
      unit(-1.0f, 1.0f), angle(0.0f, 2.0f * static_cast<float>(M_PI));
  const float r = edge / std::sqrt(3.0f);  // circumradius of an equilateral triangle
  for (size_t t = 0; t < count; ++t) {
    const glm::vec3 c(pos(rng), height(rng), pos(rng));
    // A random plane (biased towards facing the light) and a random rotation inside it.
    const glm::vec3 n = glm::normalize(glm::vec3(unit(rng), 2.0f + unit(rng), unit(rng)));
    const glm::vec3 a = glm::normalize(glm::cross(n, glm::vec3(1, 0, 0)));
    const glm::vec3 b = glm::cross(n, a);
    const float phi = angle(rng);
    for (int k = 0; k < 3; ++k) {
      const float th = phi + 2.0f * static_cast<float>(M_PI) * k / 3.0f;
      vertex(m, c + r * (std::cos(th) * a + std::sin(th) * b));
    }
    const auto base = static_cast<uint32_t>(3 * t);
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
  }
  add(s.scene, std::move(m), glm::mat4(1.0f));

  s.light.type = LightType::kDirectional;
  s.light.direction = glm::normalize(glm::vec3(0.1f, -1.0f, 0.05f));
  // Straight down, framing the whole ground vertically (half-fov 30 degrees).
  const float h = 1.1f * 0.5f * extent / std::tan(glm::radians(30.0f));
  s.camera.eye = {0, h, 0};
  s.camera.target = {0, 0, 0};
  s.camera.up = {0, 0, -1};
  s.camera.fov_deg = 60;
  s.camera.near = 0.5f * h;
  s.camera.far = 2.0f * h;
  return s;
}

}  // namespace shadow::scenes
