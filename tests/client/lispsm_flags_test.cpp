// shadowctl and LiSPSM (issue 17): --technique lispsm with --lispsm-n (only with lispsm), and the
// report's warp line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "shadowctl/args.hpp"
#include "shadowctl/report.hpp"
#include "shadowctl/request.hpp"

namespace shadow::ctl {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

TEST(LispsmFlags, TechniqueAndWarp) {
  RequestFlags f;
  f.scene = kDemoScene;
  f.lights = {"directional:1,-2,0.5"};
  f.technique = "lispsm";
  v1::RenderRequest r = build_request(f);
  EXPECT_EQ(r.shadow_map().technique(), v1::TECHNIQUE_LISPSM);
  EXPECT_FALSE(r.shadow_map().has_lispsm_n());  // the server's n_opt
  f.lispsm_n = "12.5";
  r = build_request(f);
  EXPECT_EQ(r.shadow_map().lispsm_n(), 12.5);
  f.technique = "psm";
  try {
    build_request(f);
    FAIL() << "accepted --lispsm-n with psm";
  } catch (const FlagError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--lispsm-n: only with --technique lispsm"));
  }
}

TEST(LispsmReport, PrintsTheWarp) {
  RenderResult r;
  r.light_fits.resize(1);
  r.light_fits[0].light_case = "lispsm: n 12.5 (requested), n_opt 9, gamma 60.00 deg";
  r.light_fits[0].lispsm_n = 12.5;
  EXPECT_THAT(format_report(r, {}, Timeline{}), HasSubstr("  lispsm: warp n 12.5\n"));
}

TEST(AutoReport, PrintsEachCandidate) {
  RenderResult r;
  r.light_fits.resize(1);
  LightFitReport& fit = r.light_fits[0];
  fit.light_case = "auto: lispsm: least edge sampling in the trial ...";
  fit.auto_technique = Technique::kLispsm;
  fit.auto_candidates = {{Technique::kUniform, 2048, 1, 0.169, 6.49, 0, NAN},
                         {Technique::kLispsm, 2048, 1, 0.068, 1.88, 1024, 0.00608},
                         {Technique::kPsmCube, 1024, 4, 0.041, 1.45, 512, 0.0052}};
  EXPECT_THAT(format_report(r, {}, Timeline{}),
              HasSubstr("  auto: uniform  1 x 2048^2: predicted 0.1690 per boundary pixel\n"
                        "  auto: lispsm   1 x 2048^2: predicted 0.0680 per boundary pixel, trial "
                        "at 1024^2 0.00608 (picked)\n"
                        "  auto: psm_cube 4 x 1024^2: predicted 0.0410 per boundary pixel, trial "
                        "at 512^2 0.00520\n"));
  r.light_fits[0].lispsm_n = 0;  // orthographic
  EXPECT_THAT(format_report(r, {}, Timeline{}), Not(HasSubstr("warp n")));
}

}  // namespace
}  // namespace shadow::ctl
