// Every standard view sees its scene and has both light and shadow under the oracle, so the
// bench never scores an empty or all-lit picture.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "oracle/oracle.hpp"
#include "oracle/standard_scenes.hpp"

namespace shadow::scenes {
namespace {

TEST(StandardScenes, EveryViewSeesLightAndShadow) {
  const auto all = standard_scenes();
  ASSERT_EQ(all.size(), 6u);
  for (const StandardScene& sc : all) {
    oracle::RayOracle oracle(*sc.scene);
    EXPECT_GE(sc.views.size(), 3u) << sc.name;
    for (View v : sc.views) {
      v.camera.width = 160;
      v.camera.height = 90;
      const auto vis = oracle.camera_visibility(v.camera, v.light);
      size_t seen = 0, lit = 0;
      for (float x : vis) {
        seen += !std::isnan(x);
        lit += x == 1.0f;
      }
      const double lit_share = seen ? double(lit) / seen : 0.0;
      std::printf("%-8s %-20s seen %5.1f%%, lit %5.1f%%\n", sc.name.c_str(), v.name.c_str(),
                  100.0 * seen / vis.size(), 100.0 * lit_share);
      EXPECT_GT(seen, vis.size() / 3) << sc.name << "/" << v.name;
      EXPECT_GT(lit_share, 0.05) << sc.name << "/" << v.name;
      // Light behind the camera hides most shadows behind their casters: measured >= 0.4%.
      EXPECT_LT(lit_share, 0.998) << sc.name << "/" << v.name;
    }
  }
}

}  // namespace
}  // namespace shadow::scenes
