// The built-in scene must be valid engine input and actually show shadows from its sun.
#include <cmath>

#include <gtest/gtest.h>

#include "scenes/demo_scene.hpp"

namespace shadow::scenes {
namespace {

glm::vec3 vertex(const Mesh& m, uint32_t i) {
  return {m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]};
}

TEST(DemoScene, MeshesAreWellFormedAndWoundOutward) {
  const Scene scene = demo_scene().scene;
  ASSERT_GE(scene.meshes.size(), 4u);
  for (size_t k = 0; k < scene.meshes.size(); ++k) {
    const Mesh& m = scene.meshes[k];
    SCOPED_TRACE("mesh " + std::to_string(k));
    ASSERT_GT(m.triangle_count(), 0u);
    ASSERT_EQ(m.indices.size() % 3, 0u);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    ASSERT_EQ(m.uvs.size() / 2, m.vertex_count());
    for (uint32_t i : m.indices) ASSERT_LT(i, m.vertex_count());
    for (size_t t = 0; t < m.triangle_count(); ++t) {
      const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
      const glm::vec3 n = glm::cross(vertex(m, b) - vertex(m, a), vertex(m, c) - vertex(m, a));
      ASSERT_GT(glm::length(n), 0.0f) << "degenerate triangle " << t;
      const glm::vec3 vn(m.normals[3 * a], m.normals[3 * a + 1], m.normals[3 * a + 2]);
      ASSERT_NEAR(glm::length(vn), 1.0f, 1e-5f);
      ASSERT_GT(glm::dot(n, vn), 0.0f) << "triangle " << t << " winds against its normal";
    }
  }
}

TEST(DemoScene, ObjectsStandOnTheGroundInsideIt) {
  const Scene scene = demo_scene().scene;
  ASSERT_GE(scene.instances.size(), 5u);
  const Instance& ground = scene.instances[0];
  EXPECT_TRUE(ground.receives_shadows);
  for (size_t k = 1; k < scene.instances.size(); ++k) {
    const Instance& inst = scene.instances[k];
    SCOPED_TRACE("instance " + std::to_string(k));
    EXPECT_TRUE(inst.casts_shadows);
    const Mesh& m = scene.meshes[inst.mesh];
    float lowest = INFINITY, reach = 0;
    for (uint32_t i = 0; i < m.vertex_count(); ++i) {
      const glm::vec3 p = glm::vec3(inst.transform * glm::vec4(vertex(m, i), 1.0f));
      lowest = std::min(lowest, p.y);
      reach = std::max({reach, std::abs(p.x), std::abs(p.z)});
    }
    EXPECT_NEAR(lowest, 0.0f, 1e-5f);
    EXPECT_LT(reach, 12.0f);
  }
}

TEST(DemoScene, SunAndCameraFrameTheObjects) {
  const DemoSetup demo = demo_scene();
  EXPECT_EQ(demo.light.type, LightType::kDirectional);
  EXPECT_NEAR(glm::length(demo.light.direction), 1.0f, 1e-6f);
  EXPECT_LT(demo.light.direction.y, -0.5f);  // high enough to light the ground
  EXPECT_GT(glm::length(glm::vec2(demo.light.direction.x, demo.light.direction.z)), 0.3f);
  // The camera looks down at the scene centre from above the ground and within its range.
  const Camera& c = demo.camera;
  EXPECT_GT(c.eye.y, 1.0f);
  EXPECT_LT(glm::length(c.target - glm::vec3(0, 1, 0)), 2.0f);
  EXPECT_LT(glm::length(c.eye - c.target), c.far);
  EXPECT_GT(c.near, 0.0f);
  EXPECT_GT(c.fov_deg, 0.0f);
  EXPECT_LT(c.fov_deg, 180.0f);
}

}  // namespace
}  // namespace shadow::scenes
