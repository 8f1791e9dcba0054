// TECHNIQUE_VIRTUAL through the engine (issue 53): both kernel profiles give the same bits; a
// pool too small for the view's pages makes the farthest pixels read coarser levels (counted),
// or refuses the request where it asks; a pool below a page per level is refused by name.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "engine_fixture.hpp"
#include "oracle/standard_scenes.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

RenderRequest street_view(FilterKind filter = FilterKind::kHard) {
  const scenes::StandardScene s = scenes::street();
  RenderRequest r;
  r.scene = s.scene;
  r.camera = s.views[0].camera;  // overview
  r.camera.width = 320, r.camera.height = 180;
  r.lights = {s.views[0].light};
  r.filter.kind = filter;
  r.shadow_map.technique = Technique::kVirtual;
  r.shadow_map.size = 16384;
  r.products = {Product::kVisibility};
  return r;
}

TEST(Virtual, BothKernelProfilesGiveTheSameBits) {
  for (FilterKind filter : {FilterKind::kHard, FilterKind::kPcf2x2, FilterKind::kPoisson}) {
    const RenderRequest r = street_view(filter);
    const RenderResult cpu = testing::engine("cpu").render(r);
    const RenderResult gpu = testing::engine("gpu").render(r);
    ASSERT_TRUE(cpu.virtual_pages && gpu.virtual_pages);
    EXPECT_EQ(*cpu.virtual_pages, *gpu.virtual_pages);
    EXPECT_GT(cpu.virtual_pages->resident, 20u);
    const std::vector<float>& a = cpu.textures.at(0).data;
    const std::vector<float>& b = gpu.textures.at(0).data;
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << int(filter);
  }
}

TEST(Virtual, AShortPoolCoarsensTheFarthestPixels) {
  RenderRequest r = street_view();
  const RenderResult full = testing::engine().render(r);
  ASSERT_TRUE(full.virtual_pages);
  const uint64_t marked = full.virtual_pages->requested;
  EXPECT_EQ(full.virtual_pages->resident, marked);
  EXPECT_EQ(full.virtual_pages->coarsened_pixels, 0u);
  EXPECT_EQ(full.virtual_pages->pool_bytes, 1024u * 65536u);
  r.shadow_map.virtual_pool_pages = uint32_t(marked / 2);
  const RenderResult half = testing::engine().render(r);
  ASSERT_TRUE(half.virtual_pages);
  EXPECT_LE(half.virtual_pages->requested, marked / 2);
  EXPECT_EQ(half.virtual_pages->resident, half.virtual_pages->requested);
  EXPECT_GT(half.virtual_pages->coarsened_pixels, 0u);
  EXPECT_LT(half.virtual_pages->coarsened_pixels, 320u * 180u);
  // Coarser, not lost: the shadows stay, a little blockier.
  size_t shadowed_full = 0, shadowed_half = 0, differ = 0;
  for (size_t i = 0; i < full.textures[0].data.size(); ++i) {
    const float f = full.textures[0].data[i], h = half.textures[0].data[i];
    shadowed_full += f < 0.5f, shadowed_half += h < 0.5f, differ += (f < 0.5f) != (h < 0.5f);
  }
  EXPECT_GT(shadowed_full, 320u * 180u / 20);
  EXPECT_NEAR(double(shadowed_half) / shadowed_full, 1.0, 0.1);
  EXPECT_LT(differ, shadowed_full / 10);
  // A pool of a page or two per level: most pixels read the coarsest levels, none falls off them.
  r.shadow_map.virtual_pool_pages = 16;
  const RenderResult tiny = testing::engine().render(r);
  size_t shadowed_tiny = 0;
  for (float v : tiny.textures[0].data) shadowed_tiny += v < 0.5f;
  EXPECT_LE(tiny.virtual_pages->requested, 16u);
  EXPECT_NEAR(double(shadowed_tiny) / shadowed_full, 1.0, 0.5);
  std::printf("%llu pages marked; a pool of %u: %llu pages, %llu pixels coarsened\n",
              (unsigned long long)marked, uint32_t(marked / 2),
              (unsigned long long)half.virtual_pages->requested,
              (unsigned long long)half.virtual_pages->coarsened_pixels);
  r.shadow_map.virtual_refuse_coarsening = true;
  try {
    testing::engine().render(r);
    ADD_FAILURE() << "a short pool with coarsening refused was taken";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "shadow_map.virtual_pool_pages");
  }
}

TEST(Virtual, APoolBelowAPagePerLevelIsRefused) {
  RenderRequest r = street_view();
  r.shadow_map.virtual_pool_pages = 2;
  try {
    testing::engine().render(r);
    ADD_FAILURE() << "a two-page pool was taken";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.field(), "shadow_map.virtual_pool_pages");
    EXPECT_NE(std::string(e.what()).find("a page per level"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace shadow
