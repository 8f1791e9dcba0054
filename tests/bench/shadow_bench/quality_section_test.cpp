// shadow-bench's quality section: a goal's cost is its probe plus the fixed run of the
// configuration it picked, and no cost counts the bench's own texel-density pass.
#include <gtest/gtest.h>

#include <sstream>

#include "case.hpp"
#include "quality_section.hpp"

namespace shadow::bench {
namespace {

Case with_passes(const std::string& variant, std::map<std::string, double> passes) {
  Case c;
  c.scene = "street", c.view = "grazing", c.variant = variant;
  c.passes = std::move(passes);
  for (const auto& [name, ms] : c.passes) c.device_ms += ms;
  return c;
}

TEST(BenchQualitySection, CostsLeaveOutTheDensityAndSumTheFixedRunsOfTheSameWork) {
  const Case fixed = with_passes("lispsm 1024", {{"gbuffer.raster", 2},
                                                 {"shadow_map.raster", 4},
                                                 {"visibility.shadow_test", 0.5},
                                                 {"texel_density.footprint", 9},
                                                 {"light1.texel_density.footprint", 3}});
  EXPECT_DOUBLE_EQ(configuration_ms(fixed), 6.5);
  const Case probe = with_passes("uniform 512", {{"gbuffer.raster", 2.5},
                                                 {"shadow_map.bin", 0.25},
                                                 {"shadow_map.raster", 1},
                                                 {"visibility.shadow_test", 0.75},
                                                 {"texel_density.footprint", 9}});
  Case goal = with_passes("quality error 1.0%", {{"gbuffer.raster", 3},
                                                 {"quality_probe.boundary.count", 0.125},
                                                 {"quality_probe.shadow_map.raster", 8},
                                                 {"quality_probe.visibility.shadow_test", 8},
                                                 {"shadow_map.raster", 7},
                                                 {"texel_density.footprint", 11}});
  goal.goal = {Quality::Goal::kMaxError, 0.01};
  QualityPick pick;
  pick.technique = Technique::kLispsm, pick.size = 1024;
  goal.quality = pick;
  const Case other = with_passes("lispsm 2048", {{"shadow_map.raster", 50}});
  // The picked run's 6.5, the probe's map and test as uniform 512 ran them (2), the count.
  EXPECT_DOUBLE_EQ(goal_cost_ms(goal, {&other, &probe, &fixed}), 6.5 + 2 + 0.125);
  // The probe's own map taken (uniform 512 picked): its map and test are counted once.
  pick.technique = Technique::kUniform, pick.size = 512;
  goal.quality = pick;
  goal.reused = {"shadow_map", "visibility.shadow_test"};
  EXPECT_DOUBLE_EQ(goal_cost_ms(goal, {&probe, &fixed}), 2.5 + 2 + 0.125);
  // Without the picked configuration's fixed run, or the probe's: the goal's own.
  goal.quality->size = 4096;
  EXPECT_DOUBLE_EQ(goal_cost_ms(goal, {&probe, &fixed}), 3 + 0.125 + 8 + 8 + 7);
  goal.quality = pick;
  EXPECT_DOUBLE_EQ(goal_cost_ms(goal, {&fixed}), 3 + 0.125 + 8 + 8 + 7);
}

// The error prediction's ceiling: the same rule on the same predicted times, each candidate's
// error the one its fixed run measured, kept where the sweep has no such run.
TEST(BenchQualitySection, AKnownErrorPicksByTheSameRule) {
  const auto measured = [](const std::string& variant, size_t wrong) {
    Case c = with_passes(variant, {{"shadow_map.raster", 1}});
    c.error.both_valid = 1000, c.error.misclassified = wrong;
    return c;
  };
  const Case u512 = measured("uniform 512", 5), l1024 = measured("lispsm 1024", 20);
  Case goal = with_passes("quality error 1.0%", {});
  goal.goal = {Quality::Goal::kMaxError, 0.01};
  QualityPick pick;
  pick.technique = Technique::kLispsm, pick.size = 1024;
  pick.candidates = {{Technique::kUniform, 512, 0.02, 3, 2},
                     {Technique::kLispsm, 1024, 0.008, 9, 4},
                     {Technique::kLispsm, 2048, 0.004, 20, 8}};
  goal.quality = pick;
  goal.reused = {"scene"};
  // Uniform 512 measured 0.5%: the cheapest to meet 1%; it takes the probe's map and test.
  std::optional<Case> known = with_measured_errors(goal, {&u512, &l1024});
  ASSERT_TRUE(known.has_value());
  EXPECT_EQ(known->quality->technique, Technique::kUniform);
  EXPECT_EQ(known->quality->size, 512u);
  EXPECT_EQ(known->reused, (std::vector<std::string>{"shadow_map", "visibility.shadow_test"}));
  // Without its run uniform 512 keeps its 2%; LiSPSM 1024 measured 2%: LiSPSM 2048, predicted.
  known = with_measured_errors(goal, {&l1024});
  ASSERT_TRUE(known.has_value());
  EXPECT_EQ(known->quality->technique, Technique::kLispsm);
  EXPECT_EQ(known->quality->size, 2048u);
  EXPECT_TRUE(known->reused.empty());
  goal.quality->candidates.clear();
  EXPECT_FALSE(with_measured_errors(goal, {&u512}).has_value());
}

}  // namespace
}  // namespace shadow::bench
