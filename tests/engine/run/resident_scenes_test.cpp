// ResidentScenes without a device: held scenes come back without an upload, least recently used
// out first under the budget, an entry whose scene is gone is dropped, an over-budget scene is
// never kept.
#include <gtest/gtest.h>

#include "engine/run/resident_scenes.hpp"

namespace shadow {
namespace {

std::shared_ptr<const Scene> scene_of(size_t floats) {
  auto s = std::make_shared<Scene>();
  s->meshes.emplace_back();
  s->meshes[0].positions.assign(floats, 0.0f);
  return s;
}

TEST(ResidentScenes, KeepsHeldScenesUnderTheBudget) {
  ResidentScenes resident(2 * 400);  // two scenes of 100 floats
  int uploads = 0;
  const auto upload = [&] {
    ++uploads;
    return std::shared_ptr<const SceneBuffers>();
  };
  const auto a = scene_of(100), b = scene_of(100), c = scene_of(100);
  bool held = true;
  resident.get(a, upload, held);
  EXPECT_FALSE(held);
  resident.get(a, upload, held);
  EXPECT_TRUE(held);
  EXPECT_EQ(uploads, 1);
  resident.get(b, upload, held);
  resident.get(a, upload, held);  // a is now the most recently used
  resident.get(c, upload, held);  // b goes
  EXPECT_EQ(resident.bytes(), 800u);
  resident.get(a, upload, held);
  EXPECT_TRUE(held);
  resident.get(b, upload, held);
  EXPECT_FALSE(held);
  EXPECT_EQ(uploads, 4);
}

TEST(ResidentScenes, DropsGoneScenesAndNeverKeepsOversized) {
  ResidentScenes resident(1000);
  const auto upload = [] { return std::shared_ptr<const SceneBuffers>(); };
  bool held = false;
  auto a = scene_of(100);
  resident.get(a, upload, held);
  EXPECT_EQ(resident.bytes(), 400u);
  a.reset();  // left the scene cache and every request
  const auto small = scene_of(10);
  resident.get(small, upload, held);
  EXPECT_EQ(resident.bytes(), 40u);
  const auto big = scene_of(1000);
  resident.get(big, upload, held);
  resident.get(big, upload, held);
  EXPECT_FALSE(held);
  EXPECT_EQ(resident.bytes(), 40u);
}

}  // namespace
}  // namespace shadow
