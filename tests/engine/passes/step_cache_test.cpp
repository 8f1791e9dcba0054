// The step cache (engine/passes/step_cache.hpp): a slot holds the key of the result in it, a step
// takes it only while the cache keeps and the key is the same, and a key changes with every
// declared input of its step (the raster's here; sequence_test.cpp has the others through whole
// frames).
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "engine/passes/rasterizer.hpp"
#include "engine/passes/step_cache.hpp"

namespace shadow {
namespace {

TEST(StepCache, TakesAResultOnlyWhileKeepingAndForTheSameKey) {
  StepCache cache;
  Timeline t;
  cache.made("raster:shadow_map", 7);
  EXPECT_FALSE(cache.take("raster:shadow_map", 7, "shadow_map", t));  // not keeping: nothing kept
  cache.keep(true);
  EXPECT_FALSE(cache.take("raster:shadow_map", 7, "shadow_map", t));  // empty: neither
  cache.made("raster:shadow_map", 7);
  EXPECT_TRUE(cache.take("raster:shadow_map", 7, "shadow_map", t));   // a hit
  EXPECT_FALSE(cache.take("raster:shadow_map", 8, "shadow_map", t));  // a miss forgets the slot
  EXPECT_FALSE(cache.take("raster:shadow_map", 7, "shadow_map", t));
  cache.made("raster:shadow_map", 8);
  cache.forget("raster:shadow_map");  // overwritten by a step that keeps nothing
  EXPECT_FALSE(cache.take("raster:shadow_map", 8, "shadow_map", t));
  cache.made("raster:shadow_map", 8);
  cache.keep(true);  // a new sequence starts empty
  EXPECT_FALSE(cache.take("raster:shadow_map", 8, "shadow_map", t));
  EXPECT_EQ(t.reused(), std::vector<std::string>{"shadow_map"});
  EXPECT_EQ(t.reran(), std::vector<std::string>{"shadow_map"});
}

TEST(StepCache, KeysAreBitsFieldByField) {
  EXPECT_EQ(StepKey{}.add(1.0f).add(2u).value(), StepKey{}.add(1.0f).add(2u).value());
  EXPECT_NE(StepKey{}.add(0.0f).value(), StepKey{}.add(-0.0f).value());
  EXPECT_NE(StepKey{}.add(std::string("ab")).add(std::string("c")).value(),
            StepKey{}.add(std::string("a")).add(std::string("bc")).value());
  Light a, b;
  EXPECT_EQ(StepKey{}.add(a).value(), StepKey{}.add(b).value());
  b.cone_angle_deg += 1;
  EXPECT_NE(StepKey{}.add(a).value(), StepKey{}.add(b).value());
  Filter f, g;
  g.csm.damping += 1;
  EXPECT_NE(StepKey{}.add(f).value(), StepKey{}.add(g).value());
}

// Changing any declared input of the raster step changes its key; changing nothing does not.
TEST(StepCache, TheRasterKeyChangesWithEveryDeclaredInput) {
  struct Inputs {
    uint64_t scene = 3;
    std::vector<DrawItem> draws = std::vector<DrawItem>(2, DrawItem{});
    uint32_t width = 512, height = 256;
    bool ids = false;
    WorldBias bias;
    std::string options = "-DTILE=64";
    uint64_t key() const { return raster_key(scene, draws, width, height, ids, bias, options); }
  };
  const Inputs base;
  EXPECT_EQ(Inputs{}.key(), base.key());
  const std::vector<std::pair<const char*, std::function<void(Inputs&)>>> changes = {
      {"scene", [](Inputs& i) { i.scene = 4; }},
      {"a draw's matrix", [](Inputs& i) { i.draws[1].to_clip[3][0] = 0.5f; }},
      {"a draw's instance", [](Inputs& i) { i.draws[0].instance = 1; }},
      {"a draw's flags", [](Inputs& i) { i.draws[0].flags = 1; }},
      {"the draws", [](Inputs& i) { i.draws.pop_back(); }},
      {"width", [](Inputs& i) { i.width = 256; }},
      {"height", [](Inputs& i) { i.height = 512; }},
      {"ids", [](Inputs& i) { i.ids = true; }},
      {"bias matrix", [](Inputs& i) { i.bias.world_to_ndc[2][2] = 2.0f; }},
      {"bias light", [](Inputs& i) { i.bias.light.disk = 0.1f; }},
      {"bias constant", [](Inputs& i) { i.bias.constant = 0.01f; }},
      {"bias texel", [](Inputs& i) { i.bias.texel = 1.0f; }},
      {"bias map size", [](Inputs& i) { i.bias.map_size = 2048; }},
      {"build options", [](Inputs& i) { i.options += " -DHIZ=1"; }},
  };
  for (const auto& [what, change] : changes) {
    Inputs changed;
    change(changed);
    EXPECT_NE(changed.key(), base.key()) << what;
  }
}

}  // namespace
}  // namespace shadow
