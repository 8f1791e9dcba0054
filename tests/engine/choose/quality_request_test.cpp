// Quality goals through Engine::render on the occluder scene: the pick is reported and is what
// ran (the map's size, the technique's light case), and validation names each bad field.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "engine/choose/calibration.hpp"
#include "engine/choose/quality_pick.hpp"
#include "engine/engine.hpp"
#include "engine/plan/cost.hpp"
#include "engine/plan/plan.hpp"
#include "occluder_scene.hpp"

namespace shadow {
namespace {

RenderRequest goal(Quality::Goal g, double value) {
  RenderRequest r = testing::occluder_request();
  r.camera.width = 160;
  r.camera.height = 120;
  r.products = {Product::kShadowMap, Product::kVisibility};
  r.quality = {g, value};
  return r;
}

TEST(QualityRequest, ThePickIsReportedAndIsWhatRan) {
  for (const RenderRequest& r :
       {goal(Quality::Goal::kMaxError, 1.0), goal(Quality::Goal::kMaxError, 1e-6),
        goal(Quality::Goal::kMaxDeviceMs, 1e6)}) {
    const RenderResult res = testing::engine().render(r);
    ASSERT_TRUE(res.quality.has_value());
    const QualityPick& q = *res.quality;
    std::printf("%s\n", q.reason.c_str());
    EXPECT_EQ(res.textures[0].width, q.size);  // the shadow map
    EXPECT_NE(q.reason.find(std::to_string(q.size)), std::string::npos);
    // The pick is the rule's choice among the candidates reported, with their predictions.
    ASSERT_FALSE(q.candidates.empty());
    const QualityCandidate& chosen = choose_candidate(q.candidates, r.quality);
    EXPECT_EQ(chosen.technique, q.technique);
    EXPECT_EQ(chosen.size, q.size);
    EXPECT_EQ(chosen.predicted_error, q.predicted_error);
    EXPECT_EQ(chosen.predicted_device_ms, q.predicted_device_ms);
    EXPECT_TRUE(chosen.raster_load_priced);
    // A raster load was measured for exactly the techniques whose candidates it priced.
    for (Technique t : quality_techniques(r)) {
      const std::string pass = std::string("quality_probe.load.") + technique_label(t) + ".setup";
      const bool ran = std::find(res.passes.begin(), res.passes.end(), pass) != res.passes.end();
      const bool priced =
          std::any_of(q.candidates.begin(), q.candidates.end(), [&](const QualityCandidate& c) {
            return c.technique == t && c.raster_load_priced &&
                   !(t == Technique::kUniform && c.size == kQualityProbeSize);
          });
      EXPECT_EQ(ran, priced) << technique_label(t);
    }
    ASSERT_EQ(res.light_fits.size(), 1u);
    const std::string& light_case = res.light_fits[0].light_case;
    if (q.technique == Technique::kLispsm) {
      EXPECT_EQ(light_case.rfind("lispsm", 0), 0u) << light_case;
    }
    if (q.technique == Technique::kUniform) {
      EXPECT_EQ(light_case.rfind("uniform", 0), 0u) << light_case;
    }
  }
  // Any error allowed: the smallest map; none small enough: not met, the most accurate.
  const RenderResult loose = testing::engine().render(goal(Quality::Goal::kMaxError, 1.0));
  EXPECT_EQ(loose.quality->size, 512u);
  EXPECT_TRUE(loose.quality->goal_met);
  const RenderResult tight = testing::engine().render(goal(Quality::Goal::kMaxError, 1e-6));
  EXPECT_FALSE(tight.quality->goal_met);
  EXPECT_GT(tight.quality->size, 512u);
  // Without a goal, no pick.
  RenderRequest plain = goal(Quality::Goal::kNone, 0);
  EXPECT_FALSE(testing::engine().render(plain).quality.has_value());
}

bool has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// A goal that picks the probe's map (uniform 512: any error allowed) takes the probe's map and,
// with the hard filter and one light, its hard test, instead of drawing them again: the products
// are bit-identical to the same request without a goal, and `reused` names the steps taken.
TEST(QualityRequest, APickOfTheProbesMapTakesItFromTheProbe) {
  for (FilterKind filter : {FilterKind::kHard, FilterKind::kPcf2x2}) {
    for (size_t lights : {1, 2}) {
      RenderRequest r = goal(Quality::Goal::kMaxError, 1.0);
      r.filter.kind = filter;
      if (lights == 2) {
        r.lights.push_back(r.lights[0]);
        r.lights[1].direction = glm::normalize(glm::vec3(0.3f, -1, 0.2f));
      }
      const RenderResult res = testing::engine().render(r);
      ASSERT_TRUE(res.quality.has_value());
      ASSERT_EQ(res.quality->technique, Technique::kUniform);
      ASSERT_EQ(res.quality->size, kQualityProbeSize);
      RenderRequest plain = with_pick(r, *res.quality);
      const RenderResult fresh = testing::engine().render(plain);
      ASSERT_EQ(res.textures.size(), fresh.textures.size());
      for (size_t i = 0; i < res.textures.size(); ++i) {  // bit for bit, NaNs included
        const std::vector<float>&a = res.textures[i].data, &b = fresh.textures[i].data;
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0)
            << res.textures[i].name;
      }
      EXPECT_TRUE(fresh.reused.empty());
      const std::string light0 = lights == 2 ? "light0." : "";
      EXPECT_TRUE(has(res.reused, light0 + "shadow_map")) << lights;
      if (lights == 2) {
        EXPECT_TRUE(has(res.reused, "light1.shadow_map"));
      }
      const bool test_taken = filter == FilterKind::kHard && lights == 1;
      EXPECT_EQ(has(res.reused, "visibility.shadow_test"), test_taken);
      EXPECT_FALSE(has(res.passes, light0 + "shadow_map.raster"));  // nothing of it ran again
    }
  }
  // Another pick draws its own map and runs its own test (a warped one may take the probe's depth
  // range).
  const RenderResult finer = testing::engine().render(goal(Quality::Goal::kMaxError, 1e-6));
  EXPECT_GT(finer.quality->size, kQualityProbeSize);
  EXPECT_FALSE(has(finer.reused, "shadow_map"));
  EXPECT_FALSE(has(finer.reused, "visibility.shadow_test"));
  EXPECT_TRUE(has(finer.passes, "shadow_map.raster"));
}

// A warped pick (fitted to the view's depth range) takes the range the probe measured instead of
// measuring it again, and its products are those of the same request without a goal. Uniform is
// made hopeless (its rates 1000x) so that the goal picks PSM or LiSPSM.
TEST(QualityRequest, AWarpedPickTakesTheProbesDepthRange) {
  const Calibration& built_in = Calibration::built_in();
  Calibration::Table table = built_in.table();
  for (CalibrationBin& bin : table.at(Technique::kUniform)) bin.per_boundary *= 1000;
  Engine engine(EngineOptions{.calibration = std::make_shared<Calibration>(
                                  table, built_in.times(), built_in.error_margins())});
  const RenderRequest r = goal(Quality::Goal::kMaxError, 1e-6);
  const RenderResult res = engine.render(r);
  ASSERT_TRUE(res.quality.has_value());
  ASSERT_NE(res.quality->technique, Technique::kUniform) << res.quality->reason;
  EXPECT_EQ(res.reused, std::vector<std::string>{"depth_range"});
  EXPECT_FALSE(has(res.passes, "depth_range.reduce"));
  EXPECT_TRUE(has(res.passes, "quality_probe.depth_range.read"));  // the probe's hard test's
  EXPECT_FALSE(has(res.passes, "quality_probe.depth_range.reduce"));
  const RenderResult alone = engine.render(with_pick(r, *res.quality));
  EXPECT_TRUE(has(alone.passes, "depth_range.reduce"));
  ASSERT_EQ(res.textures.size(), alone.textures.size());
  for (size_t i = 0; i < res.textures.size(); ++i) {  // bit for bit, NaNs included
    const std::vector<float>&a = res.textures[i].data, &b = alone.textures[i].data;
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << res.textures[i].name;
  }
}

// The probe runs before any candidate: its predicted time (at the calibration's rates, without
// the camera view the run takes over) is in every candidate's, and a cost limit its admission
// estimate alone exceeds refuses the goal (RESOURCE_EXHAUSTED naming quality) before anything
// runs.
TEST(QualityRequest, TheProbeIsAdmittedAndCounted) {
  const RenderRequest r = goal(Quality::Goal::kMaxError, 0.01);
  const RenderResult res = testing::engine().render(r);
  ASSERT_TRUE(res.quality.has_value());
  const RenderRequest ran = with_pick(r, *res.quality);
  const RenderRequest probe = quality_probe(r);
  EXPECT_EQ(probe.shadow_map.size, kQualityProbeSize);
  EXPECT_EQ(probe.products, std::vector<Product>{Product::kVisibility});
  const Calibration& calibration = Calibration::built_in();
  Plan to_run = make_plan(ran);  // what the pick takes from the probe does not run again
  const size_t steps = to_run.steps.size();
  std::erase_if(to_run.steps,
                [&](const Step& s) { return taken_from_probe(ran, make_plan(ran), s.kind); });
  EXPECT_EQ(to_run.steps.size() < steps, ran.shadow_map.size == kQualityProbeSize);
  // The pick is the probe's own map, so no raster load of a map it draws enters its time.
  ASSERT_EQ(ran.shadow_map.size, kQualityProbeSize);
  const PredictedTime candidate = calibration.predict_time(ran, to_run);
  Plan beyond_view = make_plan(probe);
  std::erase_if(beyond_view.steps, [](const Step& s) { return s.kind == StepKind::kCameraView; });
  // The pick drew no map, so no raster load was measured; admission counts every measure.
  const PredictedTime probe_predicted = calibration.predict_time(probe, beyond_view);
  const double load_maps = double(quality_techniques(r).size() * r.lights.size());
  const double probe_ms = estimate_cost(probe, make_plan(probe)).ms + load_passes_ms(r, load_maps);
  for (const QualityCandidate& c : res.quality->candidates)
    EXPECT_EQ(c.raster_load_priced, c.technique == Technique::kUniform && c.size == 512);
  std::printf("[ probe    ] predicted %.2f ms (admission %.2f), the pick's %.2f, reported %.2f\n",
              probe_predicted.p90_ms, probe_ms, candidate.p90_ms, res.quality->predicted_device_ms);
  EXPECT_GT(probe_predicted.typical_ms, 0.0);
  EXPECT_GT(probe_predicted.p90_ms, probe_predicted.typical_ms);  // every margin is above 1
  EXPECT_LT(probe_predicted.p90_ms, calibration.predict_time(probe, make_plan(probe)).p90_ms);
  EXPECT_NEAR(res.quality->predicted_device_ms, candidate.p90_ms + probe_predicted.p90_ms,
              1e-12 * res.quality->predicted_device_ms);
  // The reported candidate of the pick carries both times.
  const auto picked = std::find_if(
      res.quality->candidates.begin(), res.quality->candidates.end(), [&](const auto& c) {
        return c.technique == res.quality->technique && c.size == res.quality->size;
      });
  ASSERT_NE(picked, res.quality->candidates.end());
  EXPECT_NEAR(picked->typical_device_ms, candidate.typical_ms + probe_predicted.typical_ms,
              1e-12 * picked->typical_device_ms);
  // The map taken from the probe reports its raster load: the same as drawing it anew.
  const RenderResult fixed = testing::engine().render(ran);
  EXPECT_GT(res.light_fits[0].raster_box_pixels, 0u);
  EXPECT_EQ(res.light_fits[0].raster_box_pixels, fixed.light_fits[0].raster_box_pixels);
  EXPECT_EQ(res.light_fits[0].raster_overlaps, fixed.light_fits[0].raster_overlaps);

  Engine tight(EngineOptions{.max_request_cost_ms = probe_ms / 2});
  try {
    tight.render(r);
    ADD_FAILURE() << "a goal whose probe is over the cost limit ran";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "quality");
    EXPECT_NE(std::string(e.what()).find("even the goal's probe"), std::string::npos) << e.what();
  }
}

TEST(QualityRequest, InvalidGoalsNameTheirField) {
  for (double v : {0.0, -0.1, 1.5, double(NAN)})
    EXPECT_EQ(testing::refused_field(goal(Quality::Goal::kMaxError, v)), "quality.max_error") << v;
  for (double v : {0.0, -5.0, 1e9, double(INFINITY)})
    EXPECT_EQ(testing::refused_field(goal(Quality::Goal::kMaxDeviceMs, v)), "quality.max_device_ms")
        << v;
  RenderRequest r = goal(Quality::Goal::kMaxError, 0.01);
  r.shadow_map.technique = Technique::kPsm;  // the goal picks it
  EXPECT_EQ(testing::refused_field(r), "shadow_map.technique");
  r.shadow_map.technique = Technique::kAuto;
  EXPECT_EQ(testing::refused_field(r), "(accepted)");
  r.lights[0].type = LightType::kPoint;
  r.lights[0].position = {0, 5, 0};
  EXPECT_EQ(testing::refused_field(r), "lights[0].point");
}

}  // namespace
}  // namespace shadow
