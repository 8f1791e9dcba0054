// The runner's pure parts, without a device: the ledger that holds the plan's steps to their
// declared reads and writes, and the order the readback hands textures back in.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>

#include "engine/plan/light_request.hpp"
#include "engine/plan/plan.hpp"
#include "engine/run/readback.hpp"
#include "engine/run/step_resources.hpp"

namespace shadow {
namespace {

RenderRequest request(Technique technique, FilterKind filter, std::vector<Product> products,
                      LightType light = LightType::kDirectional) {
  auto scene = std::make_shared<Scene>();
  Mesh m;
  m.positions = {-1, 0, -1, 1, 0, -1, 0, 0, 1};
  m.indices = {0, 1, 2};
  m.uvs = {0, 0, 1, 0, 0, 1};
  scene->meshes.push_back(m);
  scene->instances.push_back(Instance{});
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 3, 3};
  r.lights[0].type = light;
  r.lights[0].position = {0, 2, 0};
  r.shadow_map.technique = technique;
  r.filter.kind = filter;
  r.products = std::move(products);
  return r;
}

// Every step of `plan` entered and done in order; the steps that start a light.
std::vector<std::string> walk(const Plan& plan) {
  StepLedger ledger;
  std::vector<std::string> starts;
  for (const Step& step : plan.steps) {
    if (ledger.enter(step)) starts.push_back(step.name);
    ledger.done(step);
  }
  return starts;
}

TEST(StepLedger, EveryPlannedStepReadsWhatAnEarlierStepWrote) {
  const std::vector<Product> all = {Product::kShadowMap,      Product::kVisibility,
                                    Product::kPosition,       Product::kTexelDensity,
                                    Product::kShadowMapMips,  Product::kShadowMapSat,
                                    Product::kVisibilityMips, Product::kVisibilitySat};
  for (Technique t : {Technique::kUniform, Technique::kPsm, Technique::kLispsm, Technique::kAuto})
    for (FilterKind f : {FilterKind::kHard, FilterKind::kPcf2x2, FilterKind::kPcss,
                         FilterKind::kBlur, FilterKind::kCsm, FilterKind::kPcssCsm})
      EXPECT_NO_THROW(walk(make_plan(request(t, f, all)))) << technique_label(t) << " " << int(f);
  for (Technique t : {Technique::kCube, Technique::kPsm, Technique::kPsmCube})
    EXPECT_NO_THROW(walk(make_plan(request(
        t, FilterKind::kHard, {Product::kShadowMap, Product::kVisibility, Product::kTexelDensity},
        LightType::kPoint))));
  for (FilterKind f : {FilterKind::kHard, FilterKind::kAtlasSat, FilterKind::kAtlasMip})
    EXPECT_NO_THROW(walk(
        make_plan(request(Technique::kUniform, f,
                          {Product::kVisibility, Product::kShadowAtlas, Product::kShadowAtlasMips,
                           Product::kShadowAtlasSat, Product::kAtlasUvs}))));
  RenderRequest csm = request(Technique::kUniform, FilterKind::kPcssCsm,
                              {Product::kVisibility, Product::kBlockerDepth, Product::kCsmBasis});
  EXPECT_NO_THROW(walk(make_plan(csm)));
}

TEST(StepLedger, EachLightStartsWithNoResourcesButTheSharedOnes) {
  RenderRequest r = request(Technique::kUniform, FilterKind::kHard,
                            {Product::kVisibility, Product::kShadowMap, Product::kPosition});
  r.lights.push_back(r.lights[0]);
  r.lights.push_back(r.lights[0]);
  const Plan plan = make_plan(r);
  // The first light's steps follow the shared ones without starting anything.
  const std::vector<std::string> starts = walk(plan);
  ASSERT_EQ(starts.size(), 2u);
  EXPECT_EQ(starts[0].rfind("light1.", 0), 0u) << starts[0];
  EXPECT_EQ(starts[1].rfind("light2.", 0), 0u) << starts[1];

  StepLedger ledger;
  for (const Step& step : plan.steps) {
    const bool started = ledger.enter(step);
    if (started) {  // nothing of the last light's is left, the camera view is
      EXPECT_FALSE(ledger.written(Resource::kLightMaps, false));
      EXPECT_FALSE(ledger.written(Resource::kVisibility, false));
      EXPECT_TRUE(ledger.written(Resource::kCameraView, true));
      EXPECT_EQ(ledger.light(), step.light);
    }
    ledger.done(step);
  }
  EXPECT_TRUE(ledger.written(Resource::kVisibility, false));
}

TEST(StepLedger, AStepBeforeWhatItReadsIsALogicError) {
  Plan plan = make_plan(request(Technique::kUniform, FilterKind::kHard, {Product::kVisibility}));
  // The visibility test moved before the maps it reads.
  auto vis = std::find_if(plan.steps.begin(), plan.steps.end(),
                          [](const Step& s) { return s.kind == StepKind::kVisibility; });
  auto maps = std::find_if(plan.steps.begin(), plan.steps.end(),
                           [](const Step& s) { return s.kind == StepKind::kRenderMaps; });
  ASSERT_NE(vis, plan.steps.end());
  ASSERT_NE(maps, plan.steps.end());
  std::iter_swap(vis, maps);
  try {
    walk(plan);
    FAIL() << "no error";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("visibility.shadow_test"), std::string::npos) << e.what();
  }
}

TEST(Readback, OrdersTexturesByProductThenLight) {
  RenderRequest r;
  r.products = {Product::kVisibility, Product::kShadowMap, Product::kPosition};
  const auto tex = [](std::string name, Product kind) {
    Texture t;
    t.name = std::move(name);
    t.kind = kind;
    return t;
  };
  // As two lights' readbacks return them: each light's products, the shared ones with the first.
  std::vector<Texture> textures = {
      tex("visibility_light0", Product::kVisibility), tex("shadowmap_light0", Product::kShadowMap),
      tex("position", Product::kPosition), tex("visibility_light1", Product::kVisibility),
      tex("shadowmap_light1", Product::kShadowMap)};
  order_products(r, textures);
  std::vector<std::string> names;
  for (const Texture& t : textures) names.push_back(t.name);
  EXPECT_EQ(names, (std::vector<std::string>{"visibility_light0", "visibility_light1",
                                             "shadowmap_light0", "shadowmap_light1", "position"}));
}

}  // namespace
}  // namespace shadow
