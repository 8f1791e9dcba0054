// shadowctl's filter flags: --filter and its per-kind settings, --receiver-class, and the
// mip/SAT product names.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "flag_error.hpp"
#include "scenes/demo_scene.hpp"
#include "shadowctl/args.hpp"
#include "shadowctl/request.hpp"

namespace shadow::ctl {
namespace {

using ::testing::HasSubstr;

RequestFlags demo() {
  RequestFlags f;
  f.scene = kDemoScene;
  return f;
}

TEST(FilterFlags, EachKindWithItsSettings) {
  RequestFlags f = demo();
  EXPECT_FALSE(build_request(f).has_filter());  // absent = hard on the server
  f.filter = "poisson";
  f.pcf_taps = "24";
  f.pcf_radius = "3.5";
  f.pcf_rotate = "off";
  v1::RenderRequest r = build_request(f);
  ASSERT_TRUE(r.filter().has_poisson());
  EXPECT_EQ(r.filter().poisson().taps(), 24u);
  EXPECT_EQ(r.filter().poisson().radius(), 3.5f);
  EXPECT_FALSE(r.filter().poisson().rotate());

  f = demo();
  f.filter = "pcss";
  f.pcss_blocker_samples = "8";
  f.pcss_filter_samples = "40";
  r = build_request(f);
  EXPECT_EQ(r.filter().pcss().blocker_samples(), 8u);
  EXPECT_EQ(r.filter().pcss().filter_samples(), 40u);
  EXPECT_FALSE(r.filter().pcss().has_rotate());

  f = demo();
  f.filter = "blur";
  f.blur_radius = "6";
  f.blur_passes = "3";
  f.receiver_classes = {"0:2"};
  r = build_request(f);
  EXPECT_EQ(r.filter().blur().radius(), 6u);
  EXPECT_EQ(r.filter().blur().passes(), 3u);
  EXPECT_EQ(r.scene().instances(0).receiver_class(), 2u);
  EXPECT_FALSE(r.scene().instances(1).has_receiver_class());

  f = demo();
  f.filter = "pcf2x2";
  EXPECT_TRUE(build_request(f).filter().has_pcf2x2());
}

TEST(FilterFlags, MistakesNameTheFlag) {
  RequestFlags f = demo();
  f.filter = "gauss";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--filter: unknown filter 'gauss'"));
  f.filter = "pcss";
  f.pcf_taps = "8";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--pcf-taps: only with --filter poisson"));
  f = demo();
  f.blur_radius = "3";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--blur-radius: only with --filter blur"));
  f = demo();
  f.filter = "blur";
  f.receiver_classes = {"999:1"};
  EXPECT_THAT(flag_error_of(f), HasSubstr("--receiver-class: instance 999 is not in the scene"));
  f.receiver_classes = {"1-2"};
  EXPECT_THAT(flag_error_of(f), HasSubstr("--receiver-class: expected INSTANCE:CLASS"));
  f = demo();
  f.filter = "poisson";
  f.pcf_rotate = "maybe";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--pcf-rotate: expected on or off"));
}

// Flags that would change nothing are refused, naming what they need (issue 44).
TEST(FilterFlags, FlagsThatWouldChangeNothingAreRefused) {
  // Blur without a receiver class is the hard test, bit for bit.
  RequestFlags f = demo();
  f.filter = "blur";
  EXPECT_THAT(flag_error_of(f),
              HasSubstr("--filter: blur softens the shadow only on instances given a receiver "
                        "class, and none has one: add --receiver-class INSTANCE:CLASS"));
  f.receiver_classes = {"0:0"};
  EXPECT_EQ(flag_error_of(f), "(no error)");
  // ...and a receiver class without blur is read by no filter.
  f.filter = "pcf2x2";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--receiver-class: only with --filter blur"));
  f.filter.reset();
  EXPECT_THAT(flag_error_of(f), HasSubstr("--receiver-class: only with --filter blur"));

  // The light's size is read by the filters with a penumbra only.
  f = demo();
  f.light_size = "1";
  EXPECT_THAT(flag_error_of(f),
              HasSubstr("--light-size: only with --filter pcss, pcss_csm, atlas_sat or atlas_mip "
                        "(the penumbra's light size; --filter hard does not read it)"));
  f.filter = "poisson";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--filter poisson does not read it"));
  for (const char* soft : {"pcss", "pcss_csm"}) {
    f.filter = soft;
    EXPECT_EQ(flag_error_of(f), "(no error)") << soft;
  }

  // The atlas settings without an atlas.
  f = demo();
  f.atlas_tile = "64";
  EXPECT_THAT(flag_error_of(f),
              HasSubstr("--atlas-tile: only with an atlas: --products shadow_atlas"));
  f.atlas_tile.reset();
  f.atlas_generate_uvs = true;
  EXPECT_THAT(flag_error_of(f), HasSubstr("--atlas-generate-uvs: only with an atlas"));
  f.products = "visibility,shadow_atlas";
  EXPECT_EQ(flag_error_of(f), "(no error)");
}

// --atlas-density: world units per atlas texel, sent as AtlasSettings.texel_world_size; only with
// an atlas, not with --atlas-tile. Without --fit the request leaves the fit unset (the server
// gives an atlas MAP_FIT_SCENE); --fit view is sent as named, for the server to refuse.
TEST(FilterFlags, AtlasDensity) {
  RequestFlags f = demo();
  f.filter = "atlas_sat";
  v1::RenderRequest r = build_request(f);
  EXPECT_FALSE(r.atlas().has_texel_world_size());
  EXPECT_FALSE(r.atlas().has_tile_size());
  EXPECT_EQ(r.shadow_map().fit(), v1::MAP_FIT_UNSPECIFIED);
  f.atlas_density = "0.05";
  r = build_request(f);
  EXPECT_EQ(r.atlas().texel_world_size(), double(0.05f));
  EXPECT_FALSE(r.atlas().has_tile_size());
  f.fit = "view";
  EXPECT_EQ(build_request(f).shadow_map().fit(), v1::MAP_FIT_VIEW);
  f.fit.reset();

  f.atlas_density = "fine";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--atlas-density: expected a finite number"));
  f.atlas_density = "0.05";
  f.atlas_tile = "64";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--atlas-density: not with --atlas-tile"));
  f.atlas_tile.reset();
  f.filter.reset();
  EXPECT_THAT(flag_error_of(f),
              HasSubstr("--atlas-density: only with an atlas: --products shadow_atlas"));
  f.products = "shadow_atlas";
  EXPECT_EQ(flag_error_of(f), "(no error)");
}

// builtin:demo brings a sun 0.53 degrees across, so PCSS needs no --light-size on it; --light
// replaces that sun whole, and then PCSS asks for --light-size as on a file scene.
TEST(FilterFlags, SoftFiltersNeedALightSizeWhereverLightGivesTheLight) {
  RequestFlags f = demo();
  f.filter = "pcss";
  v1::RenderRequest r = build_request(f);
  EXPECT_EQ(r.lights(0).size(), scenes::demo_scene().light.size);
  for (const char* light : {"spot:0,10,0:0,-1,0:40", "directional:0,-1,0"}) {
    f.lights = {light};
    EXPECT_THAT(flag_error_of(f),
                HasSubstr("--light-size: required by --filter pcss: light 0 has no size"))
        << light;
    f.light_size = "0.5";
    r = build_request(f);
    EXPECT_EQ(r.lights(0).size(), 0.5f) << light;
    f.light_size.reset();
  }
  // Without a soft filter the replaced sun is simply hard.
  f.filter.reset();
  EXPECT_EQ(build_request(f).lights(0).size(), 0.0f);
}

TEST(FilterFlags, CsmSettingsGoToTheirKind) {
  RequestFlags f = demo();
  f.filter = "csm";
  f.csm_terms = "12";
  f.csm_storage = "float16";
  f.csm_lookup = "sat";
  f.csm_window = "6.5";
  f.csm_damping = "0.5";
  f.csm_depth_offset = "0.01";
  f.csm_scale = "2";
  v1::RenderRequest r = build_request(f);
  ASSERT_TRUE(r.filter().has_csm());
  EXPECT_EQ(r.filter().csm().terms(), 12u);
  EXPECT_EQ(r.filter().csm().storage(), v1::CSM_STORAGE_FLOAT16);
  EXPECT_EQ(r.filter().csm().lookup(), v1::CSM_LOOKUP_SAT);
  EXPECT_EQ(r.filter().csm().window(), 6.5f);
  EXPECT_EQ(r.filter().csm().damping(), 0.5f);
  EXPECT_EQ(r.filter().csm().depth_offset(), 0.01f);
  EXPECT_EQ(r.filter().csm().scale(), 2.0f);
  f = demo();
  f.filter = "pcss_csm";
  f.csm_terms = "4";
  r = build_request(f);
  ASSERT_TRUE(r.filter().has_pcss_csm());
  EXPECT_EQ(r.filter().pcss_csm().terms(), 4u);
  EXPECT_FALSE(r.filter().pcss_csm().has_damping());  // the server's default
  f.csm_window = "4";                                 // pcss_csm's window is PCSS's penumbra
  EXPECT_THAT(flag_error_of(f), HasSubstr("--csm-window: only with --filter csm"));
  f = demo();
  f.csm_terms = "4";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--csm-terms: only with --filter csm or pcss_csm"));
  f.filter = "csm";
  f.csm_storage = "double";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--csm-storage: unknown storage 'double'"));
  f.csm_storage.reset();
  f.csm_lookup = "box";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--csm-lookup: unknown lookup 'box'"));
  EXPECT_EQ(parse_products("csm_basis,blocker_depth", "--products"),
            (std::vector<Product>{Product::kCsmBasis, Product::kBlockerDepth}));
}

TEST(FilterFlags, MipAndSatProducts) {
  const auto p =
      parse_products("shadowmap_mips,shadowmap_sat,visibility_mips,visibility_sat", "--products");
  EXPECT_EQ(p, (std::vector<Product>{Product::kShadowMapMips, Product::kShadowMapSat,
                                     Product::kVisibilityMips, Product::kVisibilitySat}));
}

}  // namespace
}  // namespace shadow::ctl
