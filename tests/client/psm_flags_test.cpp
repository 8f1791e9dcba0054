// shadowctl's PSM flags: --technique psm or psm_cube with --psm-casters, --psm-near and
// --psm-virtual-slide, which are refused without them.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "flag_error.hpp"
#include "shadowctl/args.hpp"
#include "shadowctl/request.hpp"

namespace shadow::ctl {
namespace {

using ::testing::HasSubstr;

// Each test runs with both PSM techniques: the flag value and what the request carries.
struct PsmTechnique {
  const char* flag;
  v1::Technique wire;
};

class PsmFlags : public ::testing::TestWithParam<PsmTechnique> {};

TEST_P(PsmFlags, TechniqueAndOptions) {
  RequestFlags f;
  f.scene = kDemoScene;
  f.technique = GetParam().flag;
  v1::RenderRequest r = build_request(f);
  EXPECT_EQ(r.shadow_map().technique(), GetParam().wire);
  EXPECT_EQ(r.shadow_map().psm_casters(), v1::PSM_CASTERS_UNSPECIFIED);  // server default
  f.psm_casters = "slide-back";
  f.psm_near = "camera";
  r = build_request(f);
  EXPECT_EQ(r.shadow_map().psm_casters(), v1::PSM_CASTERS_SLIDE_BACK);
  EXPECT_EQ(r.shadow_map().psm_near(), v1::PSM_NEAR_CAMERA);
  f.psm_casters = "inverse-projection";
  EXPECT_EQ(build_request(f).shadow_map().psm_casters(), v1::PSM_CASTERS_INVERSE_PROJECTION);
}

TEST_P(PsmFlags, VirtualSlideBackAndWorldBias) {
  RequestFlags f;
  f.scene = kDemoScene;
  f.technique = GetParam().flag;
  f.psm_near = "virtual-slide-back";
  f.psm_virtual_slide = "7.5";
  f.bias_world_constant = "0.01";
  f.bias_world_texel = "2";
  const v1::RenderRequest r = build_request(f);
  EXPECT_EQ(r.shadow_map().psm_near(), v1::PSM_NEAR_VIRTUAL_SLIDE_BACK);
  EXPECT_EQ(r.shadow_map().psm_virtual_slide(), 7.5);
  EXPECT_EQ(r.shadow_map().bias_world_constant(), 0.01f);
  EXPECT_EQ(r.shadow_map().bias_world_texel(), 2.0f);
  f.psm_near = "receivers";
  EXPECT_THAT(flag_error_of(f),
              HasSubstr("--psm-virtual-slide: only with --psm-near virtual-slide-back"));
  f.psm_near = "sideways";
  EXPECT_THAT(flag_error_of(f), HasSubstr("virtual-slide-back"));
}

INSTANTIATE_TEST_SUITE_P(Techniques, PsmFlags,
                         ::testing::Values(PsmTechnique{"psm", v1::TECHNIQUE_PSM},
                                           PsmTechnique{"psm_cube", v1::TECHNIQUE_PSM_CUBE}),
                         [](const auto& info) { return std::string(info.param.flag); });

TEST(PsmFlagsRefused, OptionsNeedPsm) {
  RequestFlags f;
  f.scene = kDemoScene;
  f.psm_casters = "slide-back";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--psm-casters: only with --technique psm"));
  f.technique = "uniform";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--psm-casters: only with --technique psm"));
  f.psm_casters.reset();
  f.psm_near = "receivers";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--psm-near: only with --technique psm or psm_cube"));
  f.technique = "cube";
  f.lights = {"point:0,3,0"};
  EXPECT_THAT(flag_error_of(f), HasSubstr("--psm-near: only with --technique psm or psm_cube"));
}

}  // namespace
}  // namespace shadow::ctl
