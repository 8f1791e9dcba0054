// The planner without a device: which steps a request runs, in which order, and what they read.
#include <gtest/gtest.h>

#include "engine/plan/cost.hpp"
#include "engine/plan/light_request.hpp"
#include "engine/plan/plan.hpp"

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

// The atlas' surfaces once, before the camera view; each light filters them before the
// camera's visibility (both use the visibility passes' buffers).
TEST(Plan, AtlasBakesOnceAndFiltersPerLight) {
  EXPECT_EQ(make_plan(request({Product::kShadowAtlas, Product::kVisibility})).step_names(),
            (Names{"scene", "light_fit", "shadow_map", "atlas.bake", "atlas.visibility", "gbuffer",
                   "visibility.shadow_test", "readback"}));
  RenderRequest two = request({Product::kShadowAtlas});
  two.lights = {Light{}, Light{}};
  EXPECT_EQ(make_plan(two).step_names(),
            (Names{"scene", "light0.light_fit", "light0.shadow_map", "atlas.bake",
                   "light0.atlas.visibility", "light0.readback", "light1.light_fit",
                   "light1.shadow_map", "light1.atlas.visibility", "light1.readback"}));
}

// The atlas filters: the hard atlas, its prefilter, then the soft atlas, all once per light;
// the camera's frame only reads the soft atlas.
TEST(Plan, AtlasFiltersSoftenTheAtlasBeforeTheCameraView) {
  for (const auto& [filter, prefilter] : {std::pair{FilterKind::kAtlasSat, "atlas.sat"},
                                          std::pair{FilterKind::kAtlasMip, "atlas.mips"}}) {
    const Plan plan = make_plan(request({Product::kVisibility}, filter));
    EXPECT_EQ(plan.step_names(),
              (Names{"scene", "light_fit", "shadow_map", "atlas.bake", "atlas.visibility",
                     prefilter, "atlas.soften", "gbuffer", "visibility.atlas", "readback"}));
    EXPECT_EQ(plan.steps[8].reads.back(), Resource::kAtlasSoft);
  }
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
  r.lights[0].type = LightType::kPoint;
  EXPECT_FALSE(make_plan(r).has(StepKind::kDepthRange));
}

// AUTO may draw PSM's cube only where cube faces serve the whole request: a directional or spot
// light, a filter with a bounded reach, camera-space products. Admission then prices up to six
// faces' triangles over one map's texels.
TEST(Plan, AutoMayDrawPsmsCubeOnlyWhereCubeFacesServe) {
  RenderRequest r =
      request({Product::kVisibility, Product::kTexelDensity}, FilterKind::kHard, Technique::kAuto);
  r.lights = {Light{}};
  EXPECT_TRUE(auto_may_cube(r));
  for (FilterKind f : {FilterKind::kPcf2x2, FilterKind::kPoisson, FilterKind::kCsm}) {
    RenderRequest g = r;
    g.filter.kind = f;
    EXPECT_TRUE(auto_may_cube(g)) << int(f);
  }
  for (FilterKind f : {FilterKind::kPcss, FilterKind::kPcssCsm, FilterKind::kBlur,
                       FilterKind::kAtlasSat, FilterKind::kAtlasMip}) {
    RenderRequest g = r;
    g.filter.kind = f;
    EXPECT_FALSE(auto_may_cube(g)) << int(f);
  }
  for (Product p : {Product::kShadowMap, Product::kShadowMapMips, Product::kShadowMapSat,
                    Product::kShadowAtlas}) {
    RenderRequest g = r;
    g.products.push_back(p);
    EXPECT_FALSE(auto_may_cube(g)) << int(p);
  }
  RenderRequest point = r, fixed = r, spot = r;
  point.lights[0].type = LightType::kPoint;  // its own cube, at the size asked for
  fixed.shadow_map.technique = Technique::kPsm;
  spot.lights[0].type = LightType::kSpot;
  EXPECT_FALSE(auto_may_cube(point));
  EXPECT_FALSE(auto_may_cube(fixed));
  EXPECT_TRUE(auto_may_cube(spot));

  auto scene = std::make_shared<Scene>();
  scene->meshes.resize(1);
  scene->meshes[0].positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  scene->meshes[0].indices = {0, 1, 2};
  scene->instances.resize(1);
  r.scene = scene;
  RenderRequest one = r;
  one.shadow_map.technique = Technique::kUniform;
  const auto units = [](const RenderRequest& q) {
    for (const StepCost& s : estimate_cost(q, make_plan(q)).steps)
      if (s.step == "shadow_map") return s.units;
    throw std::runtime_error("no shadow_map step");
  };
  const auto cube = units(r), single = units(one);
  EXPECT_EQ(cube[size_t(CostRate::kTriangle)], 6 * single[size_t(CostRate::kTriangle)]);
  EXPECT_EQ(cube[size_t(CostRate::kMapTexel)], single[size_t(CostRate::kMapTexel)]);
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
  EXPECT_EQ(plan.csm_prefilter, CsmPrefilter::kMips);
  EXPECT_FALSE(plan.csm_blocker);
  RenderRequest sat = request({Product::kVisibility}, FilterKind::kCsm);
  sat.filter.csm.lookup = CsmLookup::kSat;  // box lookups read summed-area tables instead
  EXPECT_EQ(make_plan(sat).csm_prefilter, CsmPrefilter::kSat);
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
  EXPECT_EQ(plan.csm_prefilter, CsmPrefilter::kNone);
  EXPECT_FALSE(plan.csm_blocker);
}

}  // namespace
}  // namespace shadow

namespace shadow {
namespace {

Light sun(glm::vec3 direction) {
  Light l;
  l.direction = direction;
  return l;
}

// Several lights: the scene and the camera view once, then each light's steps with its prefix,
// each ending with its readback (the position, which needs no light, with the first).
TEST(Plan, SeveralLightsShareTheSceneAndTheCameraView) {
  RenderRequest r = request({Product::kVisibility, Product::kPosition});
  r.lights = {sun({0, -1, 0}), sun({1, -1, 0}), sun({0, -1, 1})};
  const Plan plan = make_plan(r);
  EXPECT_EQ(plan.step_names(),
            (Names{"scene", "light0.light_fit", "light0.shadow_map", "gbuffer",
                   "light0.visibility.shadow_test", "light0.readback", "light1.light_fit",
                   "light1.shadow_map", "light1.visibility.shadow_test", "light1.readback",
                   "light2.light_fit", "light2.shadow_map", "light2.visibility.shadow_test",
                   "light2.readback"}));
  EXPECT_EQ(plan.steps[5].reads,
            (std::vector<Resource>{Resource::kVisibility, Resource::kCameraView}));
  EXPECT_EQ(plan.steps[9].reads, (std::vector<Resource>{Resource::kVisibility}));
  EXPECT_EQ(plan.steps[9].light, 1u);
  EXPECT_EQ(plan.steps[3].light, 0u);  // the camera view belongs to no light
}

// A light that measures the receivers (LiSPSM) puts the camera view before its fit; a later
// light reuses it.
TEST(Plan, TheCameraViewComesWhereTheFirstLightNeedsIt) {
  RenderRequest r = request({Product::kShadowMap}, FilterKind::kHard, Technique::kLispsm);
  r.lights = {sun({0, -1, 0}), sun({1, -1, 0})};
  EXPECT_EQ(make_plan(r).step_names(),
            (Names{"scene", "gbuffer", "depth_range", "light0.light_fit", "light0.shadow_map",
                   "light0.readback", "light1.light_fit", "light1.shadow_map", "light1.readback"}));
}

// The default technique is resolved per light: a point light's cube beside a sun's uniform map.
TEST(Plan, TheDefaultTechniqueIsResolvedPerLight) {
  EXPECT_EQ(resolved_technique(Technique::kDefault, LightType::kPoint), Technique::kCube);
  EXPECT_EQ(resolved_technique(Technique::kDefault, LightType::kSpot), Technique::kUniform);
  EXPECT_EQ(resolved_technique(Technique::kDefault, LightType::kDirectional), Technique::kUniform);
  EXPECT_EQ(resolved_technique(Technique::kPsm, LightType::kPoint), Technique::kPsm);
  RenderRequest r = request({Product::kShadowMap}, FilterKind::kHard, Technique::kDefault);
  Light point;
  point.type = LightType::kPoint;
  r.lights = {sun({0, -1, 0}), point};
  EXPECT_EQ(for_light(r, 0).shadow_map.technique, Technique::kUniform);
  EXPECT_EQ(for_light(r, 1).shadow_map.technique, Technique::kCube);
  EXPECT_EQ(for_light(r, 1).lights.size(), 1u);
  EXPECT_EQ(for_light(r, 1).lights[0].type, LightType::kPoint);
}

// POSITION alone needs no light: the camera's steps only.
TEST(Plan, NoLightPositionOnly) {
  RenderRequest r = request({Product::kPosition});
  r.lights.clear();
  EXPECT_EQ(make_plan(r).step_names(), (Names{"scene", "gbuffer", "readback"}));
}

}  // namespace
}  // namespace shadow
