// PSM on the wire: technique and options both ways (PSM and PSM_CUBE), documented defaults,
// unknown values named, and the reply header's light-fit report (with the PSM cube's texel-size
// range) through make_header and the assembler.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "wire/convert.hpp"
#include "wire/errors.hpp"
#include "wire/result_assembler.hpp"
#include "wire/result_slicer.hpp"

namespace shadow::convert {
namespace {

ShadowMapSettings round_trip(const ShadowMapSettings& s) {
  v1::ShadowMapSettings wire;
  EXPECT_TRUE(wire.ParseFromString(to_proto(s).SerializeAsString()));
  return from_proto(wire);
}

TEST(PsmConvert, TechniqueAndOptionsRoundTrip) {
  ShadowMapSettings s;
  s.technique = Technique::kPsm;
  s.psm = {PsmCasters::kSlideBack, PsmNear::kCamera};
  ShadowMapSettings t = round_trip(s);
  EXPECT_EQ(t.technique, Technique::kPsm);
  EXPECT_EQ(t.psm.casters, PsmCasters::kSlideBack);
  EXPECT_EQ(t.psm.near, PsmNear::kCamera);
  s.psm = {};
  t = round_trip(s);
  EXPECT_EQ(t.psm.casters, PsmCasters::kInverseProjection);
  EXPECT_EQ(t.psm.near, PsmNear::kReceivers);
  s.technique = Technique::kUniform;
  EXPECT_EQ(round_trip(s).technique, Technique::kUniform);
}

// The PSM options are PSM_CUBE's too: written and read for it exactly as for PSM.
TEST(PsmConvert, PsmCubeCarriesThePsmOptions) {
  ShadowMapSettings s;
  s.technique = Technique::kPsmCube;
  s.size = 912;
  s.psm = {PsmCasters::kSlideBack, PsmNear::kVirtualSlideBack, 4.25};
  const v1::ShadowMapSettings wire = to_proto(s);
  EXPECT_EQ(wire.technique(), v1::TECHNIQUE_PSM_CUBE);
  EXPECT_EQ(wire.psm_casters(), v1::PSM_CASTERS_SLIDE_BACK);
  EXPECT_EQ(wire.psm_near(), v1::PSM_NEAR_VIRTUAL_SLIDE_BACK);
  EXPECT_EQ(wire.psm_virtual_slide(), 4.25);
  const ShadowMapSettings t = round_trip(s);
  EXPECT_EQ(t.technique, Technique::kPsmCube);
  EXPECT_EQ(t.size, 912u);
  EXPECT_EQ(t.psm.casters, PsmCasters::kSlideBack);
  EXPECT_EQ(t.psm.near, PsmNear::kVirtualSlideBack);
  EXPECT_EQ(t.psm.virtual_slide, 4.25);
  s.psm = {PsmCasters::kInverseProjection, PsmNear::kCamera};
  EXPECT_EQ(round_trip(s).psm.near, PsmNear::kCamera);
}

TEST(PsmConvert, VirtualSlideBackAndWorldBiasRoundTrip) {
  ShadowMapSettings s;
  s.technique = Technique::kPsm;
  s.psm.near = PsmNear::kVirtualSlideBack;
  s.psm.virtual_slide = 12.5;
  s.bias_world_constant = 0.02f;
  s.bias_world_texel = 1.5f;
  const ShadowMapSettings t = round_trip(s);
  EXPECT_EQ(t.psm.near, PsmNear::kVirtualSlideBack);
  EXPECT_EQ(t.psm.virtual_slide, 12.5);
  EXPECT_EQ(t.bias_world_constant, 0.02f);
  EXPECT_EQ(t.bias_world_texel, 1.5f);
  // Absent: no world-space bias, the default slide (0).
  v1::ShadowMapSettings wire;
  wire.set_psm_near(v1::PSM_NEAR_VIRTUAL_SLIDE_BACK);
  const ShadowMapSettings d = from_proto(wire);
  EXPECT_EQ(d.psm.near, PsmNear::kVirtualSlideBack);
  EXPECT_EQ(d.psm.virtual_slide, 0.0);
  EXPECT_EQ(d.bias_world_constant, 0.0f);
  EXPECT_EQ(d.bias_world_texel, 0.0f);
}

TEST(PsmConvert, AbsentOptionsTakeTheDefaultsAndUnknownOnesAreNamed) {
  v1::ShadowMapSettings wire;
  wire.set_technique(v1::TECHNIQUE_PSM_CUBE);
  EXPECT_EQ(from_proto(wire).technique, Technique::kPsmCube);
  EXPECT_EQ(from_proto(wire).psm.near, PsmNear::kReceivers);
  wire.set_technique(v1::TECHNIQUE_PSM);
  const ShadowMapSettings s = from_proto(wire);
  EXPECT_EQ(s.technique, Technique::kPsm);
  EXPECT_EQ(s.psm.casters, PsmCasters::kInverseProjection);
  EXPECT_EQ(s.psm.near, PsmNear::kReceivers);
  wire.set_psm_casters(static_cast<v1::PsmCasterMode>(7));
  try {
    from_proto(wire);
    FAIL() << "accepted an unknown caster mode";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("shadow_map.psm_casters"), std::string::npos) << e.what();
  }
  wire.set_psm_casters(v1::PSM_CASTERS_SLIDE_BACK);
  wire.set_psm_near(static_cast<v1::PsmNearMode>(9));
  EXPECT_THROW(from_proto(wire), InvalidArgument);
}

TEST(PsmConvert, HeaderCarriesTheLightFit) {
  RenderResult r;
  r.light_fits.resize(1);
  r.light_fits[0].light_case = "directional from behind: inverted point light";
  r.light_fits[0].virtual_near = 2.5;
  r.light_fits[0].virtual_far = 60.0;
  r.light_fits[0].slide_back = 3.0;
  r.light_fits[0].light_near = -1.25;
  r.light_fits[0].light_far = 1.5;
  r.light_fits[0].raster_overlaps = 123456789012ull;  // past 32 bits
  r.light_fits[0].raster_box_pixels = 9876543210123ull;
  v1::RenderResponse response;
  *response.mutable_header() = make_header(r);
  v1::RenderResponse wire;
  ASSERT_TRUE(wire.ParseFromString(response.SerializeAsString()));
  ResultAssembler a;
  a.add(wire);
  const RenderResult back = a.finish();
  EXPECT_EQ(back.light_fits[0].light_case, r.light_fits[0].light_case);
  EXPECT_EQ(back.light_fits[0].virtual_near, 2.5);
  EXPECT_EQ(back.light_fits[0].virtual_far, 60.0);
  EXPECT_EQ(back.light_fits[0].slide_back, 3.0);
  EXPECT_EQ(back.light_fits[0].light_near, -1.25);
  EXPECT_EQ(back.light_fits[0].light_far, 1.5);
  EXPECT_EQ(back.light_fits[0].raster_overlaps, 123456789012ull);
  EXPECT_EQ(back.light_fits[0].raster_box_pixels, 9876543210123ull);
  EXPECT_EQ(back.light_fits[0].cube_texel_min, 0.0);  // not a PSM cube
  EXPECT_EQ(back.light_fits[0].cube_texel_max, 0.0);
}

TEST(PsmConvert, HeaderCarriesThePsmCubeTexelRange) {
  RenderResult r;
  r.light_fits.resize(1);
  r.light_fits[0].light_case = "psm cube: directional from the front";
  r.light_fits[0].cube_texel_min = 1.0 / 1843;
  r.light_fits[0].cube_texel_max = 1.0 / 1024;
  v1::RenderResponse response;
  *response.mutable_header() = make_header(r);
  EXPECT_EQ(response.header().light_fits(0).psm_cube_texel_min(), 1.0 / 1843);
  EXPECT_EQ(response.header().light_fits(0).psm_cube_texel_max(), 1.0 / 1024);
  v1::RenderResponse wire;
  ASSERT_TRUE(wire.ParseFromString(response.SerializeAsString()));
  ResultAssembler a;
  a.add(wire);
  const RenderResult back = a.finish();
  EXPECT_EQ(back.light_fits[0].cube_texel_min, 1.0 / 1843);
  EXPECT_EQ(back.light_fits[0].cube_texel_max, 1.0 / 1024);
}

// LiSPSM (issue 17): the technique and its warp n both ways (absent = n_opt), and the header's n.
TEST(LispsmConvert, TechniqueWarpAndHeaderRoundTrip) {
  ShadowMapSettings s;
  s.technique = Technique::kLispsm;
  EXPECT_FALSE(to_proto(s).has_lispsm_n());
  EXPECT_EQ(round_trip(s).technique, Technique::kLispsm);
  EXPECT_EQ(round_trip(s).lispsm.n, 0.0);
  s.lispsm.n = 12.5;
  EXPECT_EQ(to_proto(s).technique(), v1::TECHNIQUE_LISPSM);
  EXPECT_EQ(round_trip(s).lispsm.n, 12.5);
  RenderResult r;
  r.light_fits.resize(1);
  r.light_fits[0].light_case = "lispsm: n 12.5 (requested)";
  r.light_fits[0].lispsm_n = 12.5;
  v1::RenderResponse response;
  *response.mutable_header() = make_header(r);
  v1::RenderResponse wire;
  ASSERT_TRUE(wire.ParseFromString(response.SerializeAsString()));
  ResultAssembler a;
  a.add(wire);
  EXPECT_EQ(a.finish().light_fits[0].lispsm_n, 12.5);
}

// AUTO (issue 17): the technique both ways, and the header's pick and reason.
TEST(AutoConvert, TechniqueAndPickRoundTrip) {
  ShadowMapSettings s;
  s.technique = Technique::kAuto;
  EXPECT_EQ(to_proto(s).technique(), v1::TECHNIQUE_AUTO);
  EXPECT_EQ(round_trip(s).technique, Technique::kAuto);
  RenderResult r;
  r.light_fits.resize(1);
  r.light_fits[0].auto_technique = Technique::kLispsm;
  r.light_fits[0].auto_reason = "lispsm: predicted texel > 1 px at 15.0% of 266 samples";
  r.light_fits[0].auto_map_size = 2048;
  v1::RenderResponse response;
  *response.mutable_header() = make_header(r);
  EXPECT_EQ(response.header().light_fits(0).auto_technique(), v1::TECHNIQUE_LISPSM);
  v1::RenderResponse wire;
  ASSERT_TRUE(wire.ParseFromString(response.SerializeAsString()));
  ResultAssembler a;
  a.add(wire);
  const RenderResult back = a.finish();
  EXPECT_EQ(back.light_fits[0].auto_technique, Technique::kLispsm);
  EXPECT_EQ(back.light_fits[0].auto_reason, r.light_fits[0].auto_reason);
  EXPECT_EQ(back.light_fits[0].auto_map_size, 2048u);
  // Not AUTO: no pick.
  ResultAssembler plain;
  v1::RenderResponse none;
  none.mutable_header();
  plain.add(none);
  EXPECT_TRUE(plain.finish().light_fits.empty());
}

// A quality goal: both ways, a size beside it or no goal named, and the pick in the header.
TEST(QualityConvert, GoalAndPickRoundTrip) {
  RenderRequest plain;
  plain.products = {Product::kVisibility};
  v1::RenderRequest wire = to_proto(plain);
  wire.mutable_shadow_map()->clear_size();
  wire.mutable_quality()->set_max_error(0.02f);
  RenderRequest r = from_proto(wire);
  EXPECT_EQ(r.quality.goal, Quality::Goal::kMaxError);
  EXPECT_FLOAT_EQ(float(r.quality.value), 0.02f);
  const v1::RenderRequest back = to_proto(r);
  EXPECT_FLOAT_EQ(back.quality().max_error(), 0.02f);
  EXPECT_FALSE(back.shadow_map().has_size());  // the goal picks it
  wire.mutable_quality()->set_max_device_ms(40);
  r = from_proto(wire);
  EXPECT_EQ(r.quality.goal, Quality::Goal::kMaxDeviceMs);
  EXPECT_EQ(r.quality.value, 40.0);
  EXPECT_EQ(to_proto(r).quality().max_device_ms(), 40.0f);
  const auto field = [](const v1::RenderRequest& w) {
    try {
      from_proto(w);
    } catch (const InvalidArgument& e) {
      return e.field();
    }
    return std::string("(accepted)");
  };
  wire.mutable_shadow_map()->set_size(1024);  // the client's size would be replaced
  EXPECT_EQ(field(wire), "shadow_map.size");
  wire.mutable_shadow_map()->clear_size();
  wire.mutable_quality()->Clear();
  EXPECT_EQ(field(wire), "quality");
  wire.clear_quality();
  EXPECT_EQ(field(wire), "(accepted)");

  RenderResult result;
  result.quality = QualityPick{Technique::kLispsm,
                               1024,
                               0.004,
                               21.5,
                               true,
                               "max_error 0.5%: ...",
                               {0.025, 0.0031},
                               {{Technique::kUniform, 512, 0.012, 6.5, 4.25, false},
                                {Technique::kLispsm, 1024, 0.004, 21.5, 7.5, true}}};
  v1::RenderResponse response;
  *response.mutable_header() = make_header(result);
  v1::RenderResponse parsed;
  ASSERT_TRUE(parsed.ParseFromString(response.SerializeAsString()));
  ResultAssembler a;
  a.add(parsed);
  const RenderResult got = a.finish();
  ASSERT_TRUE(got.quality.has_value());
  EXPECT_EQ(got.quality->technique, Technique::kLispsm);
  EXPECT_EQ(got.quality->size, 1024u);
  EXPECT_EQ(got.quality->predicted_error, 0.004);
  EXPECT_EQ(got.quality->predicted_device_ms, 21.5);
  EXPECT_TRUE(got.quality->goal_met);
  EXPECT_EQ(got.quality->reason, result.quality->reason);
  EXPECT_EQ(got.quality->boundary_share, result.quality->boundary_share);
  ASSERT_EQ(got.quality->candidates.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const QualityCandidate &want = result.quality->candidates[i], &c = got.quality->candidates[i];
    EXPECT_EQ(c.technique, want.technique);
    EXPECT_EQ(c.size, want.size);
    EXPECT_EQ(c.predicted_error, want.predicted_error);
    EXPECT_EQ(c.predicted_device_ms, want.predicted_device_ms);
    EXPECT_EQ(c.typical_device_ms, want.typical_device_ms);
    EXPECT_EQ(c.raster_load_priced, want.raster_load_priced);
  }
  // Out-of-range shares and candidates are a broken stream, named.
  const auto broken = [&](const std::function<void(v1::QualityPick&)>& edit,
                          const std::string& named) {
    v1::RenderResponse r = response;
    edit(*r.mutable_header()->mutable_quality());
    ResultAssembler bad;
    try {
      bad.add(r);
      ADD_FAILURE() << named << " was accepted";
    } catch (const StreamError& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
  };
  broken([](v1::QualityPick& q) { q.set_boundary_share(1, 1.5); }, "quality.boundary_share");
  broken([](v1::QualityPick& q) { q.mutable_candidates(1)->set_technique(v1::Technique(99)); },
         "quality.candidates[1].technique");
  broken([](v1::QualityPick& q) { q.mutable_candidates(0)->set_predicted_error(-0.1); },
         "quality.candidates[0].predicted_error");
  broken([](v1::QualityPick& q) { q.mutable_candidates(0)->set_predicted_device_ms(NAN); },
         "quality.candidates[0].predicted_device_ms");
  broken([](v1::QualityPick& q) { q.mutable_candidates(1)->set_typical_device_ms(-1); },
         "quality.candidates[1].typical_device_ms");
}

}  // namespace
}  // namespace shadow::convert
