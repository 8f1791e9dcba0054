// shadowctl and PSM_CUBE: --technique psm_cube for every light kind (its PSM flags are tested
// with psm's in psm_flags_test.cpp), and the report's texel-size line for a PSM cube.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "shadowctl/args.hpp"
#include "shadowctl/report.hpp"
#include "shadowctl/request.hpp"

namespace shadow::ctl {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

TEST(PsmCubeFlags, TechniqueForEveryLightKind) {
  RequestFlags f;
  f.scene = kDemoScene;
  f.technique = "psm_cube";
  f.map_size = "912";
  for (const char* light : {"directional:1,-2,0.5", "spot:0,5,-8:0,-0.5,1:60", "point:0,3,0"}) {
    f.lights = {light};
    const v1::RenderRequest r = build_request(f);
    EXPECT_EQ(r.shadow_map().technique(), v1::TECHNIQUE_PSM_CUBE) << light;
    EXPECT_EQ(r.shadow_map().size(), 912u) << light;
    EXPECT_EQ(r.shadow_map().psm_casters(), v1::PSM_CASTERS_UNSPECIFIED) << light;
  }
}

TEST(PsmCubeReport, PrintsTheTexelRange) {
  RenderResult r;
  r.light_fits.resize(1);
  r.light_fits[0].light_case = "psm cube: directional from the front";
  r.light_fits[0].cube_texel_min = 1.0 / 1843;
  r.light_fits[0].cube_texel_max = 1.0 / 1024;
  EXPECT_THAT(format_report(r, {}, Timeline{}),
              HasSubstr("light: psm cube: directional from the front\n"
                        "  psm cube: texels 1/1843 .. 1/1024 of the unit cube's edge\n"));
  r.light_fits[0].cube_texel_min = r.light_fits[0].cube_texel_max =
      0;  // plain PSM, or its fallback
  EXPECT_THAT(format_report(r, {}, Timeline{}), Not(HasSubstr("texels")));
}

}  // namespace
}  // namespace shadow::ctl
