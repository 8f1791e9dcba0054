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

}  // namespace
}  // namespace shadow::bench
