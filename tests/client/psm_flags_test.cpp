// shadowctl's PSM flags: --technique psm with --psm-casters and --psm-near, which are refused
// without it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "shadowctl/args.hpp"
#include "shadowctl/request.hpp"

namespace shadow::ctl {
namespace {

using ::testing::HasSubstr;

std::string error_of(const RequestFlags& flags) {
  try {
    build_request(flags);
  } catch (const FlagError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PsmFlags, TechniqueAndOptions) {
  RequestFlags f;
  f.scene = kDemoScene;
  f.technique = "psm";
  v1::RenderRequest r = build_request(f);
  EXPECT_EQ(r.shadow_map().technique(), v1::TECHNIQUE_PSM);
  EXPECT_EQ(r.shadow_map().psm_casters(), v1::PSM_CASTERS_UNSPECIFIED);  // server default
  f.psm_casters = "slide-back";
  f.psm_near = "camera";
  r = build_request(f);
  EXPECT_EQ(r.shadow_map().psm_casters(), v1::PSM_CASTERS_SLIDE_BACK);
  EXPECT_EQ(r.shadow_map().psm_near(), v1::PSM_NEAR_CAMERA);
  f.psm_casters = "inverse-projection";
  EXPECT_EQ(build_request(f).shadow_map().psm_casters(), v1::PSM_CASTERS_INVERSE_PROJECTION);
}

TEST(PsmFlags, VirtualSlideBackAndWorldBias) {
  RequestFlags f;
  f.scene = kDemoScene;
  f.technique = "psm";
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
  EXPECT_THAT(error_of(f),
              HasSubstr("--psm-virtual-slide: only with --psm-near virtual-slide-back"));
  f.psm_near = "sideways";
  EXPECT_THAT(error_of(f), HasSubstr("virtual-slide-back"));
}

TEST(PsmFlags, OptionsNeedPsm) {
  RequestFlags f;
  f.scene = kDemoScene;
  f.psm_casters = "slide-back";
  EXPECT_THAT(error_of(f), HasSubstr("--psm-casters: only with --technique psm"));
  f.technique = "uniform";
  EXPECT_THAT(error_of(f), HasSubstr("--psm-casters: only with --technique psm"));
  f.psm_casters.reset();
  f.psm_near = "receivers";
  EXPECT_THAT(error_of(f), HasSubstr("--psm-near: only with --technique psm"));
}

}  // namespace
}  // namespace shadow::ctl
