// shadow-bench's map report and its "equal texels" section: the maps counted from the rendered
// cube faces (one map otherwise), texels = maps x size^2, and the section's rows (only the
// compared variants, a PSM cube's texel range as 1/N) and its summary over the views where all
// of them ran.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

#include "case.hpp"
#include "equal_texels.hpp"

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

  LightFitReport picked = cube_fit(4);  // AUTO drew PSM's cube at equal texels
  picked.auto_technique = Technique::kPsmCube;
  picked.auto_map_size = 1024;
  set_map_report(c, picked, 2048);
  EXPECT_EQ(c.map_faces, 4u);
  EXPECT_EQ(c.map_texels, 4ull * 1024 * 1024);
}

Case view_case(const std::string& view, const std::string& variant, const LightFitReport& fit,
               uint32_t size, size_t misclassified, size_t near_misclassified) {
  Case c;
  c.scene = "street";
  c.view = view;
  c.variant = variant;
  set_map_report(c, fit, size);
  c.error.both_valid = 1000, c.error.misclassified = misclassified;
  c.bands.resize(1);
  c.bands[0].to = 10;
  c.bands[0].error.both_valid = 100, c.bands[0].error.misclassified = near_misclassified;
  return c;
}

TEST(BenchEqualTexels, ComparesTheFourVariantsOnEveryView) {
  LightFitReport uniform, psm, lispsm;
  uniform.light_case = "uniform: directional";
  psm.light_case = "directional from the front: point light";
  lispsm.light_case = "lispsm: n 3 (n_opt)";
  const std::string cube = "psm_cube " + std::to_string(kPsmCubeFaceSize);
  const std::vector<Case> cases = {
      view_case("overview", "uniform 2048", uniform, 2048, 10, 2),
      view_case("overview", "uniform 1024", uniform, 1024, 20, 4),
      view_case("overview", "psm 2048", psm, 2048, 12, 1),
      view_case("overview", cube, cube_fit(5), kPsmCubeFaceSize, 8, 3),
      view_case("overview", "lispsm 2048", lispsm, 2048, 9, 1),
      view_case("spot", "uniform 2048", uniform, 2048, 5, 5),  // not all four: not summarized
  };
  std::ostringstream md;
  write_equal_texel_section(cases, md);
  const std::string s = md.str();
  EXPECT_THAT(s, HasSubstr("## Equal texels"));
  // Summary: one view with all four; psm_cube best overall (0.8%), psm and lispsm tie near.
  EXPECT_THAT(s, HasSubstr("| uniform 2048 | 1 | 1.000% | 2.000% | 0 | 0 |"));
  EXPECT_THAT(s, HasSubstr("| " + cube + " | 1 | 0.800% | 3.000% | 1 | 0 |"));
  EXPECT_THAT(s, HasSubstr("| psm 2048 | 1 | 1.200% | 1.000% | 0 | 1 |"));
  EXPECT_THAT(s, HasSubstr("| lispsm 2048 | 1 | 0.900% | 1.000% | 0 | 1 |"));
  // Rows: every compared variant on every view, with the cube's faces and texel range.
  EXPECT_THAT(s, HasSubstr("| street | overview | " + cube +
                           " | psm cube: directional from the front | 5 | 4.16 | "
                           "1/1843 .. 1/1024 |"));
  EXPECT_THAT(s, HasSubstr("| street | spot | uniform 2048 | uniform: directional | 1 | 4.19 |"));
  EXPECT_THAT(s, Not(HasSubstr("uniform 1024")));

  std::ostringstream none;
  write_equal_texel_section({cases[1]}, none);
  EXPECT_EQ(none.str(), "");
}

}  // namespace
}  // namespace shadow::bench
