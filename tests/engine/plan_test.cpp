// The planner without a device: which steps a request runs, in which order, and what they read.
#include <gtest/gtest.h>

#include "engine/plan.hpp"

namespace shadow {
namespace {

using Names = std::vector<std::string>;

RenderRequest request(std::vector<Product> products, FilterKind filter = FilterKind::kHard,
                      Technique technique = Technique::kUniform) {
  auto scene = std::make_shared<Scene>();
  scene->meshes.resize(1);
  scene->instances.resize(2);
  RenderRequest r;
  r.scene = scene;
  r.products = std::move(products);
  r.filter.kind = filter;
  r.shadow_map.technique = technique;
  return r;
}

TEST(Plan, ShadowMapAloneRunsNoCameraPass) {
  EXPECT_EQ(make_plan(request({Product::kShadowMap})).step_names(),
            (Names{"scene", "light_fit", "shadow_map", "readback"}));
}

TEST(Plan, VisibilityWithPcssIsMapGbufferPcss) {
  EXPECT_EQ(make_plan(request({Product::kVisibility}, FilterKind::kPcss)).step_names(),
            (Names{"scene", "light_fit", "shadow_map", "gbuffer", "visibility.pcss", "readback"}));
}

TEST(Plan, EachFilterHasItsVisibilityStep) {
  const std::pair<FilterKind, const char*> table[] = {{FilterKind::kHard, "visibility.shadow_test"},
                                                      {FilterKind::kPcf2x2, "visibility.pcf"},
                                                      {FilterKind::kPoisson, "visibility.pcf"},
                                                      {FilterKind::kPcss, "visibility.pcss"},
                                                      {FilterKind::kBlur, "visibility.blur"}};
  for (const auto& [filter, name] : table) {
    const Plan plan = make_plan(request({Product::kVisibility}, filter));
    EXPECT_EQ(plan.steps[4].name, name);
    EXPECT_EQ(plan.steps[4].kind, StepKind::kVisibility);
  }
}

TEST(Plan, PositionAloneNeedsNoLight) {
  EXPECT_EQ(make_plan(request({Product::kPosition})).step_names(),
            (Names{"scene", "gbuffer", "readback"}));
}

TEST(Plan, TexelDensityFitsTheLightButDrawsNoMap) {
  EXPECT_EQ(make_plan(request({Product::kTexelDensity})).step_names(),
            (Names{"scene", "light_fit", "gbuffer", "texel_density", "readback"}));
}

TEST(Plan, PsmMeasuresTheReceiversBeforeTheFitUnlessItsNearIsTheCamera) {
  RenderRequest r = request({Product::kShadowMap}, FilterKind::kHard, Technique::kPsm);
  EXPECT_EQ(make_plan(r).step_names(),
            (Names{"scene", "gbuffer", "depth_range", "light_fit", "shadow_map", "readback"}));
  const Plan plan = make_plan(r);
  EXPECT_EQ(plan.steps[3].reads, (std::vector<Resource>{Resource::kScene, Resource::kDepthRange}));
  r.shadow_map.psm.near = PsmNear::kCamera;
  EXPECT_EQ(make_plan(r).step_names(), (Names{"scene", "light_fit", "shadow_map", "readback"}));
  r.shadow_map.technique = Technique::kPsmCube;
  r.shadow_map.psm.near = PsmNear::kReceivers;
  EXPECT_TRUE(make_plan(r).has(StepKind::kDepthRange));
}

// LiSPSM's n_opt comes from the receivers' measured depth range (issue 17).
TEST(Plan, LispsmMeasuresTheReceiversBeforeTheFit) {
  const RenderRequest r = request({Product::kShadowMap}, FilterKind::kHard, Technique::kLispsm);
  EXPECT_EQ(make_plan(r).step_names(),
            (Names{"scene", "gbuffer", "depth_range", "light_fit", "shadow_map", "readback"}));
}

// AUTO may pick LiSPSM or PSM, which need the range; a point light's AUTO is its cube.
TEST(Plan, AutoMeasuresTheReceiversUnlessThePointLightsCube) {
  RenderRequest r = request({Product::kShadowMap}, FilterKind::kHard, Technique::kAuto);
  EXPECT_TRUE(make_plan(r).has(StepKind::kDepthRange));
  r.light.type = LightType::kPoint;
  EXPECT_FALSE(make_plan(r).has(StepKind::kDepthRange));
}

TEST(Plan, VisibilityOnceForAllItsProductsAndFiltersAfterIt) {
  const Plan plan =
      make_plan(request({Product::kVisibilitySat, Product::kVisibility, Product::kVisibilityMips},
                        FilterKind::kPcf2x2));
  EXPECT_EQ(plan.step_names(),
            (Names{"scene", "light_fit", "shadow_map", "gbuffer", "visibility.pcf",
                   "visibility.sat", "visibility.mips", "readback"}));
  EXPECT_EQ(plan.steps.back().reads,
            (std::vector<Resource>{Resource::kVisibilitySat, Resource::kVisibility,
                                   Resource::kVisibilityMips}));
}

TEST(Plan, MapFiltersReadTheMap) {
  const Plan plan = make_plan(request({Product::kShadowMapMips, Product::kShadowMapSat}));
  EXPECT_EQ(plan.step_names(), (Names{"scene", "light_fit", "shadow_map", "shadowmap.mips",
                                      "shadowmap.sat", "readback"}));
  EXPECT_EQ(plan.steps[3].reads, std::vector<Resource>{Resource::kLightMaps});
  EXPECT_EQ(plan.steps[4].writes, std::vector<Resource>{Resource::kMapSat});
}

TEST(Plan, BlurPlanesOnlyWithClassReceivers) {
  RenderRequest r = request({Product::kVisibility}, FilterKind::kBlur);
  EXPECT_FALSE(make_plan(r).has(StepKind::kBlurPlanes));  // no class: the hard test alone
  auto scene = std::make_shared<Scene>(*r.scene);
  scene->instances[1].receiver_class = 2;
  r.scene = scene;
  const Plan plan = make_plan(r);
  EXPECT_EQ(plan.blur_planes, 3u);
  EXPECT_EQ(plan.step_names(), (Names{"scene", "light_fit", "shadow_map", "blur_planes", "gbuffer",
                                      "visibility.blur", "readback"}));
  // Blur planes are for the blur filter only.
  r.filter.kind = FilterKind::kPcf2x2;
  EXPECT_FALSE(make_plan(r).has(StepKind::kBlurPlanes));
}

TEST(Plan, CsmFiltersReadTheBasisWithMipsAndOnlyTheChannelsTheyNeed) {
  // The prefiltered test needs sin/cos only; PCSS-CSM's blocker average the z-weighted ones too.
  Plan plan = make_plan(request({Product::kVisibility}, FilterKind::kCsm));
  EXPECT_EQ(plan.step_names(), (Names{"scene", "light_fit", "shadow_map", "csm.basis", "gbuffer",
                                      "visibility.csm", "readback"}));
  EXPECT_TRUE(plan.csm_mips);
  EXPECT_FALSE(plan.csm_blocker);
  EXPECT_EQ(plan.steps[5].reads.back(), Resource::kCsmBasis);
  plan = make_plan(request({Product::kVisibility}, FilterKind::kPcssCsm));
  EXPECT_EQ(plan.steps[5].name, "visibility.pcss_csm");
  EXPECT_TRUE(plan.csm_blocker);
  // The blocker depth comes from the visibility step, with the z-weighted channels.
  plan = make_plan(request({Product::kBlockerDepth}, FilterKind::kCsm));
  EXPECT_TRUE(plan.csm_blocker);
  EXPECT_EQ(plan.steps[5].writes,
            (std::vector<Resource>{Resource::kVisibility, Resource::kBlockerDepth}));
  EXPECT_EQ(plan.steps.back().reads, std::vector<Resource>{Resource::kBlockerDepth});
}

TEST(Plan, CsmBasisAloneHasNoMipsAndNoCameraPass) {
  const Plan plan = make_plan(request({Product::kCsmBasis}, FilterKind::kCsm));
  EXPECT_EQ(plan.step_names(),
            (Names{"scene", "light_fit", "shadow_map", "csm.basis", "readback"}));
  EXPECT_FALSE(plan.csm_mips);
  EXPECT_FALSE(plan.csm_blocker);
}

}  // namespace
}  // namespace shadow
