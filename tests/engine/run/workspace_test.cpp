// The workspace and the light fitter on their own, on a device but without the Engine (no queue,
// no admission, no warm-up): the runner runs a plan as the engine would, refuses a plan whose
// steps read before anything wrote, and the fitter fits each technique as its fit function does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/runtime.hpp"
#include "engine/light/light_space.hpp"
#include "engine/light/lispsm_fit.hpp"
#include "engine/passes/scene_buffers.hpp"
#include "engine/plan/plan.hpp"
#include "engine/run/light_fitter.hpp"
#include "engine/run/workspace.hpp"
#include "occluder_scene.hpp"

namespace shadow {
namespace {

struct Bare {
  std::shared_ptr<const cl::Device> device = std::make_shared<const cl::Device>();
  cl::ProgramCache programs{*device};
  Workspace workspace{device, programs};
};

Bare& bare() {
  static Bare b;
  return b;
}

bool same_bits(const Texture& a, const Texture& b) {
  return a.name == b.name && a.width == b.width && a.height == b.height &&
         a.data.size() == b.data.size() &&
         std::equal(a.data.begin(), a.data.end(), b.data.begin(),
                    [](float x, float y) { return std::memcmp(&x, &y, sizeof x) == 0; });
}

TEST(Workspace, RunsAPlanAsTheEngineDoes) {
  RenderRequest r = testing::occluder_request();
  r.products = {Product::kVisibility, Product::kShadowMap, Product::kTexelDensity,
                Product::kPosition};
  r.lights.push_back(r.lights[0]);
  r.lights[1].direction = {0.3f, -1, 0.2f};
  const RenderResult own = bare().workspace.render(r, make_plan(r));
  const RenderResult engine = testing::engine().render(r);
  ASSERT_EQ(own.textures.size(), engine.textures.size());
  for (size_t i = 0; i < own.textures.size(); ++i)
    EXPECT_TRUE(same_bits(own.textures[i], engine.textures[i])) << engine.textures[i].name;
  ASSERT_EQ(own.light_fits.size(), 2u);
  EXPECT_EQ(own.light_fits[0].light_case, engine.light_fits[0].light_case);
  EXPECT_EQ(own.light_fits[1].light_case, engine.light_fits[1].light_case);
  EXPECT_EQ(own.passes, engine.passes);
}

// Issue 51's runtime guard: a render whose own device time passes 3x its admitted estimate stops
// with ResourceExhausted naming both figures, and the workspace renders on.
TEST(Workspace, ARenderPastThreeTimesItsEstimateIsStopped) {
  RenderRequest r = testing::occluder_request();
  // A second of PCSS here, against a guard with 0.1 s of slack (the engine's is 2 s: a test of
  // it would depend on how busy the machine is).
  r.shadow_map.size = 8192;
  r.camera.width = r.camera.height = 2048;
  r.filter.kind = FilterKind::kPcss;
  r.filter.pcss.blocker_samples = r.filter.pcss.filter_samples = 64;
  r.lights[0].size = 2;
  RenderControl control;
  control.estimate_ms = 1e-6;  // a wrong estimate: every launch takes longer
  control.guard_slack_ms = 100;
  try {
    bare().workspace.render(r, make_plan(r), control);
    FAIL() << "rendered past its guard";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "request cost");
    const std::string why = e.what();
    // The plan's estimate, raised by what binning found the raster costs.
    EXPECT_NE(why.find("3x its admitted estimate of "), std::string::npos) << why;
    EXPECT_NE(why.find(", plus 100 ms)"), std::string::npos) << why;
    EXPECT_NE(why.find("the request has run "), std::string::npos) << why;
  }
  r.shadow_map.size = 1024;
  r.camera.width = r.camera.height = 256;
  EXPECT_FALSE(bare().workspace.render(r, make_plan(r)).textures.empty());
}

TEST(Workspace, RefusesAPlanThatReadsBeforeItWrites) {
  const RenderRequest r = testing::occluder_request();
  Plan plan = make_plan(r);
  auto vis = std::find_if(plan.steps.begin(), plan.steps.end(),
                          [](const Step& s) { return s.kind == StepKind::kVisibility; });
  auto maps = std::find_if(plan.steps.begin(), plan.steps.end(),
                           [](const Step& s) { return s.kind == StepKind::kRenderMaps; });
  ASSERT_TRUE(vis != plan.steps.end() && maps != plan.steps.end());
  std::iter_swap(vis, maps);
  EXPECT_THROW(bare().workspace.render(r, plan), std::logic_error);
  // The workspace runs the next request as if nothing happened.
  const RenderResult after = bare().workspace.render(r, make_plan(r));
  const RenderResult engine = testing::engine().render(r);
  ASSERT_EQ(after.textures.size(), engine.textures.size());
  for (size_t i = 0; i < after.textures.size(); ++i)
    EXPECT_TRUE(same_bits(after.textures[i], engine.textures[i])) << engine.textures[i].name;
}

// A LightFitter with the passes it uses and the occluder scene on the device.
struct Fitting {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  Rasterizer rasterizer{runtime, kernels};
  ViewSamplesPass view_samples{runtime, kernels};
  LightDistancePass light_distance{runtime, kernels};
  EdgeSamplingPass edge_sampling{runtime, kernels};
  cl::Buffer empty_map;
  LightFitter fitter{rasterizer, view_samples, light_distance, edge_sampling, empty_map};
  RenderRequest request = testing::occluder_request();
  Timeline timeline;
  SceneBuffers buffers{runtime, kernels, *request.scene, timeline};
  Fitting() { runtime.ensure(empty_map, sizeof(float)); }
};

Fitting& fitting() {
  static Fitting f;
  return f;
}

TEST(LightFitter, FitsEachTechniqueAsItsFitDoes) {
  Fitting& f = fitting();
  RenderRequest r = f.request;
  const std::vector<InstanceBounds> bounds = instance_bounds(*r.scene, f.buffers);

  r.shadow_map.technique = Technique::kUniform;
  const LightPlan uniform = f.fitter.fit(r, 0, f.buffers, std::nullopt, nullptr, f.timeline);
  EXPECT_FALSE(uniform.cube);
  EXPECT_TRUE(uniform.cull);
  EXPECT_EQ(uniform.light.world_to_ndc,
            fit_uniform_light(r.lights[0], r.camera, bounds).world_to_ndc);
  EXPECT_EQ(uniform.report.light_case, "uniform: directional");
  EXPECT_EQ(uniform.map_size, r.shadow_map.size);

  r.shadow_map.technique = Technique::kLispsm;
  const LightPlan lispsm = f.fitter.fit(r, 0, f.buffers, std::nullopt, nullptr, f.timeline);
  const LispsmFit expected = fit_lispsm_light(r.lights[0], r.camera, bounds, r.shadow_map.lispsm);
  EXPECT_FALSE(lispsm.cull);
  EXPECT_EQ(lispsm.light.world_to_ndc, expected.setup.world_to_ndc);
  EXPECT_EQ(lispsm.report.light_case, expected.light_case);

  RenderRequest point = r;
  point.lights[0].type = LightType::kPoint;
  point.lights[0].position = {0, 5, 0};
  point.shadow_map.technique = Technique::kCube;
  const LightPlan cube = f.fitter.fit(point, 0, f.buffers, std::nullopt, nullptr, f.timeline);
  EXPECT_TRUE(cube.cube);
  EXPECT_EQ(cube.report.light_case, "cube: point light");
  EXPECT_EQ(cube.report.cube_faces.size(), 6u);
}

TEST(LightFitter, DrawsMapsOnlyWhenAsked) {
  Fitting& f = fitting();
  RenderRequest r = f.request;
  r.shadow_map.size = 256;
  const LightPlan plan = f.fitter.fit(r, 0, f.buffers, std::nullopt, nullptr, f.timeline);
  const DrawnMaps set_up = f.fitter.draw(r, f.buffers, plan, false, 0, f.timeline);
  ASSERT_EQ(set_up.maps.size(), 1u);
  EXPECT_FALSE(f.fitter.rendered(set_up.maps[0]));  // texel density reads the matrix alone
  EXPECT_EQ(set_up.single, nullptr);
  const DrawnMaps drawn = f.fitter.draw(r, f.buffers, plan, true, 0, f.timeline);
  ASSERT_EQ(drawn.maps.size(), 1u);
  EXPECT_TRUE(f.fitter.rendered(drawn.maps[0]));
  ASSERT_NE(drawn.single, nullptr);
  EXPECT_EQ(drawn.single_draws, 2u);  // the ground and the occluder both cast, both in the map
  EXPECT_EQ(drawn.maps[0].version, drawn.single->version);
}

}  // namespace
}  // namespace shadow
