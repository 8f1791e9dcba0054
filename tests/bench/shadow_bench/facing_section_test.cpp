// shadow-bench's map report and its "light facing the camera" section: the maps counted from the
// rendered cube faces (one map otherwise), texels = maps x size^2, and the section's rows (only
// the compared variants on the facing views, a PSM cube's texel range as 1/N).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

#include "case.hpp"
#include "facing_section.hpp"

namespace shadow::bench {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

LightFitReport cube_fit(int rendered) {
  LightFitReport fit;
  fit.light_case = "psm cube: directional from the front";
  const char* names[] = {"+x", "-x", "+y", "-y", "+z", "-z"};
  for (int i = 0; i < 6; ++i) fit.cube_faces.push_back({names[i], i < rendered, ""});
  fit.cube_texel_min = 1.0 / 1843;
  fit.cube_texel_max = 1.0 / 1024;
  return fit;
}

TEST(BenchMapReport, CountsRenderedFacesOrOneMap) {
  Case c;
  set_map_report(c, cube_fit(5), 912);
  EXPECT_EQ(c.map_faces, 5u);
  EXPECT_EQ(c.map_texels, 5ull * 912 * 912);
  EXPECT_EQ(c.light_case, "psm cube: directional from the front");
  EXPECT_EQ(c.cube_texel_max, 1.0 / 1024);

  LightFitReport plain;
  plain.light_case = "uniform: directional";
  set_map_report(c, plain, 2048);  // a reused case is reset
  EXPECT_EQ(c.map_faces, 1u);
  EXPECT_EQ(c.map_texels, 2048ull * 2048);
  EXPECT_EQ(c.cube_texel_min, 0.0);

  set_map_report(c, cube_fit(0), 8192);  // a cube with no face: no texels
  EXPECT_EQ(c.map_faces, 0u);
  EXPECT_EQ(c.map_texels, 0u);
}

Case facing_case(const std::string& view, const std::string& variant, const LightFitReport& fit,
                 uint32_t size) {
  Case c;
  c.scene = "street";
  c.view = view;
  c.variant = variant;
  set_map_report(c, fit, size);
  return c;
}

TEST(BenchFacingSection, ComparesTheFacingViewsOnly) {
  LightFitReport uniform;
  uniform.light_case = "uniform: directional";
  const std::string cube = "psm_cube " + std::to_string(kPsmCubeFaceSize);
  const std::vector<Case> cases = {
      facing_case("overview", "uniform 2048", uniform, 2048),
      facing_case(kFacingView, "uniform 2048", uniform, 2048),
      facing_case(kFacingView, "uniform 1024", uniform, 1024),
      facing_case(kFacingView, cube, cube_fit(5), kPsmCubeFaceSize),
  };
  std::ostringstream md;
  write_facing_section(cases, md);
  const std::string s = md.str();
  EXPECT_THAT(s, HasSubstr("## Light facing the camera"));
  EXPECT_THAT(s, HasSubstr("| street | uniform 2048 | uniform: directional | 1 | 4.19 |  |"));
  EXPECT_THAT(s, HasSubstr("| street | " + cube +
                           " | psm cube: directional from the front | 5 | 4.16 | "
                           "1/1843 .. 1/1024 |"));
  EXPECT_THAT(s, Not(HasSubstr("uniform 1024")));
  // One uniform 2048 row: the overview's is left out.
  EXPECT_EQ(s.find("| uniform 2048 |"), s.rfind("| uniform 2048 |"));

  std::ostringstream none;
  write_facing_section({cases[0]}, none);
  EXPECT_EQ(none.str(), "");
}

}  // namespace
}  // namespace shadow::bench
