// kernels/light_distance.cl against a double-precision CPU distance computed another way (the
// plane when the foot point falls inside the triangle, else the nearest of the three edges).
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/passes/light_distance.hpp"
#include "engine/passes/rasterizer.hpp"

namespace shadow {
namespace {

double segment_distance(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b) {
  const glm::dvec3 ab = b - a;
  const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}

double triangle_distance(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
  const double h = glm::dot(p - a, n);
  const glm::dvec3 foot = p - h * n;
  // Inside when the foot lies on the inner side of all three edges.
  const bool inside = glm::dot(glm::cross(b - a, foot - a), n) >= 0 &&
                      glm::dot(glm::cross(c - b, foot - b), n) >= 0 &&
                      glm::dot(glm::cross(a - c, foot - c), n) >= 0;
  if (inside) return std::abs(h);
  return std::min(
      {segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}

TEST(LightDistance, MatchesADoublePrecisionReference) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  LightDistancePass pass(runtime, kernels);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 20; ++trial) {
    // Two instances of one random mesh (9000 triangles), the second moved and turned, and a
    // light somewhere among them: the minimum spans chunks and draws.
    Scene scene;
    Mesh m;
    for (int i = 0; i < 27000; ++i) m.positions.push_back(5.0f * u(rng));
    for (uint32_t i = 0; i < 9000 / 3; ++i)
      m.indices.insert(m.indices.end(), {3 * i, 3 * i + 1, 3 * i + 2});
    scene.meshes.push_back(m);
    scene.instances.push_back(Instance{});
    Instance moved;
    moved.transform = glm::rotate(glm::translate(glm::mat4(1.0f), {20, 1, -3}), 0.7f, {0, 1, 0});
    scene.instances.push_back(moved);
    const glm::vec3 light(8.0f * u(rng), 3.0f * u(rng), 3.0f * u(rng));

    Timeline timeline;
    SceneBuffers buffers(runtime, kernels, scene, timeline);
    auto draws = make_draws(scene, buffers, glm::mat4(1.0f), [](const Instance&) { return true; });
    const double got = pass.run(buffers, draws, light, timeline);

    double want = INFINITY;
    for (const Instance& inst : scene.instances) {
      const glm::dmat4 t(inst.transform);
      for (size_t i = 0; i < m.indices.size(); i += 3) {
        glm::dvec3 v[3];
        for (int k = 0; k < 3; ++k) {
          const float* p = &m.positions[3 * m.indices[i + k]];
          v[k] = glm::dvec3(t * glm::dvec4(p[0], p[1], p[2], 1.0));
        }
        want = std::min(want, triangle_distance(glm::dvec3(light), v[0], v[1], v[2]));
      }
    }
    // A lower bound within 1e-5 of the coordinates' size (25 here) below the true distance.
    EXPECT_LE(got, want) << trial;
    EXPECT_GE(got, want - 3e-4) << trial;
  }
}

}  // namespace
}  // namespace shadow
