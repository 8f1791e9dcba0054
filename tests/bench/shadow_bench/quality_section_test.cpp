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

TEST(BenchQualitySection, CostsLeaveOutTheDensityAndTakeThePickedConfigurationsRun) {
  const Case fixed = with_passes("lispsm 1024", {{"gbuffer.raster", 2},
                                                 {"shadow_map.raster", 4},
                                                 {"texel_density.footprint", 9},
                                                 {"light1.texel_density.footprint", 3}});
  EXPECT_DOUBLE_EQ(configuration_ms(fixed), 6);
  Case goal = with_passes("quality error 1.0%", {{"gbuffer.raster", 3},
                                                 {"quality_probe.shadow_map.raster", 1},
                                                 {"quality_probe.visibility.shadow_test", 0.5},
                                                 {"shadow_map.raster", 7},
                                                 {"texel_density.footprint", 11}});
  goal.goal = {Quality::Goal::kMaxError, 0.01};
  QualityPick pick;
  pick.technique = Technique::kLispsm, pick.size = 1024;
  goal.quality = pick;
  const Case other = with_passes("lispsm 2048", {{"shadow_map.raster", 50}});
  EXPECT_DOUBLE_EQ(goal_cost_ms(goal, {&other, &fixed}), 6 + 1.5);
  EXPECT_DOUBLE_EQ(goal_cost_ms(goal, {&other}), 3 + 1.5 + 7);  // not run on its own: the goal's
  goal.quality.reset();
  EXPECT_DOUBLE_EQ(goal_cost_ms(goal, {&fixed}), 3 + 1.5 + 7);
}

}  // namespace
}  // namespace shadow::bench
