// Perspective Shadow Maps against the Embree oracle at the configurations issue 4 lists: the
// map's depth through its own matrix, visibility against shadow rays from the engine's surface
// points, and no NaN/Inf anywhere (light_measure.hpp, with its debug switches). Bounds are the
// measured figures with a margin; every run prints the measured values.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/engine.hpp"
#include "light_measure.hpp"
#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/scenes.hpp"
#include "oracle/standard_scenes.hpp"
#include "shared_engine.hpp"

namespace shadow {
namespace {

using accuracy::engine;
using accuracy::texture;

struct PsmCase {
  std::string name;
  double angle_deg;  // light's travel vs the view direction: 0 = along it (from behind)
  double far_over_near = 600;
  bool behind_wall = false;  // a wall behind the camera whose shadow falls into view
  PsmCasters casters = PsmCasters::kInverseProjection;
  double min_depth_agree;  // fraction of texels within 1e-5 NDC of the oracle
  double max_misclassified;
};

scenes::Setup setup(const PsmCase& c) {
  return accuracy::angled_setup(c.angle_deg, c.far_over_near, c.behind_wall);
}

using accuracy::bands;
using accuracy::measure;
using accuracy::Measured;

class PsmOracle : public ::testing::TestWithParam<PsmCase> {};

TEST_P(PsmOracle, DepthAndVisibilityMatchTheOracle) {
  const PsmCase& c = GetParam();
  const scenes::Setup s = setup(c);
  const oracle::RayOracle oracle(s.scene);
  const Measured p = measure(s, oracle, Technique::kPsm, c.casters, 512, true);
  const Measured u = measure(s, oracle, Technique::kUniform, c.casters, 512, false);
  std::printf("[ psm      ] %s: %s\n[ psm      ]   depth: %s\n", c.name.c_str(),
              p.light_case.c_str(), p.depth.summary().c_str());
  std::printf("[ psm      ]   misclassified psm %.5f%%, uniform %.5f%% (oracle shadowed %zu px)\n",
              100 * p.vis.misclassified_rate(), 100 * u.vis.misclassified_rate(), p.shadowed);
  std::printf("[ psm      ]   by distance psm: %s\n[ psm      ]   uniform: %s\n", bands(p).c_str(),
              bands(u).c_str());
  EXPECT_EQ(p.vis.nan_mismatch, 0u);
  EXPECT_GE(p.depth.fraction(), c.min_depth_agree);
  EXPECT_LE(p.vis.misclassified_rate(), c.max_misclassified);
  // PSM against uniform at the same map size. Light along the view (both signs) must degrade
  // gracefully: measured +0.110 (behind) and +0.003 (front) percentage points at 512^2.
  if (c.angle_deg == 0 || c.angle_deg == 180) {
    EXPECT_LE(p.vis.misclassified_rate(), u.vis.misclassified_rate() + 0.0015);
  }
  if (c.behind_wall) {
    EXPECT_GT(p.shadowed, 20000u);  // the wall's shadow is in view
  }
}

// Measured misclassified with attached shadows against Embree with a 1e-6 ray offset (PSM 512^2,
// of 32732 px): perpendicular 0.055%, behind 1 / 5 / 30 / 60 deg 0.208 / 0.192 / 0.150 /
// 0.070%, facing 1 / 5 deg 0.003% (1 px), facing 30 / 60 deg 1.308 / 0.156%, along the view
// 0.205%, against it 0.003%, grazing 89 / 89.99 deg 0.058 / 0.055%, far/near 10 / 1e3 / 1e5 /
// 1e6 0.070 / 0.070 / 0.089 / 0.281%, the wall behind 0.082% (inverse projection) and 0.046%
// (slide-back). Facing 1 and 5 deg and against the view the light travels upward: every seen
// pixel faces away from it, so there the visibility check only tests the attached-shadow rule
// (the depth comparison still tests the map).
INSTANTIATE_TEST_SUITE_P(
    Engine, PsmOracle,
    ::testing::Values(
        PsmCase{"perpendicular", 90, 600, false, PsmCasters::kInverseProjection, 0.995, 0.00086},
        PsmCase{"behind_1deg", 1, 600, false, PsmCasters::kInverseProjection, 0.995, 0.0028},
        PsmCase{"behind_5deg", 5, 600, false, PsmCasters::kInverseProjection, 0.995, 0.0026},
        PsmCase{"behind_30deg", 30, 600, false, PsmCasters::kInverseProjection, 0.995, 0.002},
        PsmCase{"behind_60deg", 60, 600, false, PsmCasters::kInverseProjection, 0.995, 0.0011},
        PsmCase{"front_1deg", 179, 600, false, PsmCasters::kInverseProjection, 0.995, 0.00034},
        PsmCase{"front_5deg", 175, 600, false, PsmCasters::kInverseProjection, 0.995, 0.00034},
        PsmCase{"front_30deg", 150, 600, false, PsmCasters::kInverseProjection, 0.995, 0.017},
        PsmCase{"front_60deg", 120, 600, false, PsmCasters::kInverseProjection, 0.995, 0.0021},
        PsmCase{"along_view", 0, 600, false, PsmCasters::kInverseProjection, 0.995, 0.0027},
        PsmCase{"against_view", 180, 600, false, PsmCasters::kInverseProjection, 0.995, 0.00034},
        PsmCase{"grazing_behind_89deg", 89, 600, false, PsmCasters::kInverseProjection, 0.995,
                0.00089},
        PsmCase{"grazing_behind_89_99deg", 89.99, 600, false, PsmCasters::kInverseProjection, 0.995,
                0.00086},
        PsmCase{"ratio_10", 60, 10, false, PsmCasters::kInverseProjection, 0.995, 0.0011},
        PsmCase{"ratio_1e3", 60, 1e3, false, PsmCasters::kInverseProjection, 0.995, 0.0011},
        PsmCase{"ratio_1e5", 60, 1e5, false, PsmCasters::kInverseProjection, 0.995, 0.0012},
        PsmCase{"ratio_1e6", 60, 1e6, false, PsmCasters::kInverseProjection, 0.995, 0.0036},
        PsmCase{"wall_behind_inverse", 45, 600, true, PsmCasters::kInverseProjection, 0.995,
                0.0012},
        PsmCase{"wall_behind_slide_back", 45, 600, true, PsmCasters::kSlideBack, 0.995, 0.00077}),
    [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace shadow

namespace shadow {
namespace {

// A sun perpendicular to a horizontal view along -z (PSM's best case, issue 4): from the side
// (+x) at `elevation_deg`, or straight overhead at 90.
Light sun_perpendicular(float elevation_deg) {
  const float e = glm::radians(elevation_deg);
  Light l;
  l.direction = glm::normalize(glm::vec3(-std::cos(e), -std::sin(e), 0.0f));
  return l;
}

struct NearFar {
  Measured psm, uniform, uniform4096;
};

// PSM 1024^2 against uniform 1024^2 and 4096^2 on one standard view, printed whole-image and by
// distance from the eye (the paper's claim is about the near band).
NearFar run_view(const char* tag, const scenes::StandardScene& sc, const oracle::RayOracle& oracle,
                 const scenes::View& v) {
  scenes::Setup s{*sc.scene, v.camera, v.light};
  s.camera.width = 320, s.camera.height = 180;
  const uint32_t psm_size = std::getenv("PSM_SIZE") ? std::atoi(std::getenv("PSM_SIZE")) : 1024;
  NearFar r{measure(s, oracle, Technique::kPsm, PsmCasters::kInverseProjection, psm_size, true),
            measure(s, oracle, Technique::kUniform, PsmCasters::kInverseProjection, 1024, false),
            measure(s, oracle, Technique::kUniform, PsmCasters::kInverseProjection, 4096, false)};
  std::printf(
      "[ %-8s ] %s: %s; depth %s\n[ %-8s ]   misclassified psm %.4f%%, uniform %.4f%%, "
      "uniform 4096 %.4f%%\n[ %-8s ]   by distance psm 1024: %s\n[ %-8s ]   uniform 1024: %s\n"
      "[ %-8s ]   uniform 4096: %s\n",
      tag, v.name.c_str(), r.psm.light_case.c_str(), r.psm.depth.summary().c_str(), tag,
      100 * r.psm.vis.misclassified_rate(), 100 * r.uniform.vis.misclassified_rate(),
      100 * r.uniform4096.vis.misclassified_rate(), tag, bands(r.psm).c_str(), tag,
      bands(r.uniform).c_str(), tag, bands(r.uniform4096).c_str());
  EXPECT_EQ(r.psm.vis.nan_mismatch, 0u);
  return r;
}

// What one standard view measured (320x180, maps 1024^2 unless named), as regression bounds.
struct ViewBounds {
  const char* view;
  double max_misclassified;  // PSM 1024, whole image
  double max_near;           // PSM 1024, pixels within 10 m of the eye
  bool claim_holds;  // near band: PSM 1024 <= uniform 4096 (+0.05 points), the paper's claim
};

void check(const scenes::View& v, const NearFar& r, std::span<const ViewBounds> bounds) {
  const auto b = std::find_if(bounds.begin(), bounds.end(),
                              [&](const ViewBounds& x) { return v.name == x.view; });
  ASSERT_NE(b, bounds.end()) << v.name;
  const double near = r.psm.bands[0].error.misclassified_rate();
  EXPECT_LE(r.psm.vis.misclassified_rate(), b->max_misclassified) << v.name;
  EXPECT_LE(near, b->max_near) << v.name;
  if (b->claim_holds) {
    EXPECT_LE(near, r.uniform4096.bands[0].error.misclassified_rate() + 5e-4) << v.name;
  }
}

// The standard street (1.5 km, eye at 1.7 m, far/near 2e4) under each of its suns, plus two
// suns perpendicular to the view (PSM's best case).
TEST(PsmStreet, EveryViewAgainstShadowRays) {
  scenes::StandardScene street = scenes::street();
  const oracle::RayOracle oracle(*street.scene);
  street.views.push_back({"sun_side_35", street.views[0].camera, sun_perpendicular(35)});
  street.views.push_back({"sun_side_70", street.views[0].camera, sun_perpendicular(70)});
  // Measured with attached shadows (a side facing away from the sun or edge-on to it is dark)
  // against Embree with a 1e-6 ray offset, at the default slope bias (0.75 since 2026-11-27),
  // whole-image misclassified PSM 1024 vs uniform 1024 / 4096, and within 10 m:
  //   overview      0.11 vs 1.74 / 0.46%, near 0.07 vs 3.80 / 0.60%
  //   light_behind  3.21 vs 0.05 / 0.03%, near 0.14 vs 0.06 / 0.005% (claim fails; it held
  //                 against the old 1e-4 offset: near 0.06 vs 0.04 / 0.09%)
  //   light_facing  0.38 vs 0.08 / 0.03%, near 0.28 vs 0.04 / 0.005% (claim fails)
  //   grazing       3.23 vs 1.37 / 0.22%, near 3.57 vs 2.11 / 0.41% (claim fails; slope bias
  //                 1.5 lit the ground the light grazes: 7.44%, near 8.86%)
  //   sun_side_35   0.43 vs 0.91 / 0.20%, near 0 for all. This sun travels across the street:
  //                 the facades facing along it are edge-on to it, which their depth slope's
  //                 MAX_SLOPE bias lit (7.6% of the image at every size) until edge-on sides
  //                 counted as attached shadows.
  //   sun_side_70   0.06 vs 0.13 / 0.04%, near 0.04 vs 0.11 / 0.11%
  // Far misses are sampling, not bias (zero biases or a receiver-side world-space bias leave
  // them; PSM_SIZE=4096 gives 0.03/0.18/0.38/3.7% on the first four): with the sun near the view
  // direction the post-perspective light sits near the view centre and its frustum over the
  // whole receiver box spends few texels on the far facades.
  const ViewBounds bounds[] = {{"overview", 0.0015, 0.0009, true},
                               {"light_behind_camera", 0.037, 0.002, false},  // held at 1e-4
                               {"light_facing_camera", 0.005, 0.004, false},
                               {"grazing", 0.042, 0.047, false},
                               {"sun_side_35", 0.0056, 0.001, true},
                               {"sun_side_70", 0.00082, 0.00091, true}};
  for (const scenes::View& v : street.views) {
    const NearFar r = run_view("street", street, oracle, v);
    // Measured >= 99.891% (grazing). With near and far at the receiving pixels' measured range
    // (the depth-range reduction) the overview's 2.6% of far texels off by 1e-5..1e-4 NDC
    // (float evaluation of the projective matrix near Kozlov's 1/2 = infinity; 97.43% with the
    // boxes' range) are gone: 99.962%.
    EXPECT_GE(r.psm.depth.fraction(), 0.998);
    check(v, r, bounds);
  }
}

// With the measured near/far (depth_range.reduce; before: the boxes' range) the forest went
// walker 7.47 -> 5.65%, grazing 20.55 -> 13.40%, side 35 11.20 -> 11.19%, side 70 9.88 ->
// 10.07% (its near band 1.60 -> 2.01%), overview 9.66 -> 9.69%, light behind 5.45% both; the
// street views are unchanged (overview 1.119 -> 1.118%).
// The standard forest (thin trunks on hills) under each of its suns, plus two perpendicular to
// the walker's view. Measured with attached shadows at the default slope bias (0.75), whole
// image PSM 1024: overview 1.94%, walker 0.72%, light behind 4.82%, grazing 1.91% (2.68% at slope
// bias 1.5), side 35 2.64%, side 70 1.39%. The near claim holds for the walker only (PSM 1024
// within 10 m: walker 0.16 vs uniform 4096 0.32%, light behind 4.38 vs 0.61%, grazing 0.010 vs
// 0% (1.35% at 1.5), side 35 0.74 vs 0.63%, side 70 0.43 vs 0.24%), though PSM 1024 beats
// uniform 1024 near the eye except with the light behind (uniform 1024: walker 2.06%, light
// behind 2.00%, grazing 1.11%, side 35 2.19%, side 70 1.01%); the overview has no pixel within
// 10 m.
TEST(PsmForest, EveryViewAgainstShadowRays) {
  scenes::StandardScene forest = scenes::forest();
  const oracle::RayOracle oracle(*forest.scene);
  const Camera walker = forest.views[1].camera;  // near-horizontal view along -z
  forest.views.push_back({"walker_sun_side_35", walker, sun_perpendicular(35)});
  forest.views.push_back({"walker_sun_side_70", walker, sun_perpendicular(70)});
  const ViewBounds bounds[] = {{"overview", 0.026, 0.001, true},  // no near pixels
                               {"walker", 0.01, 0.002, true},
                               {"light_behind_camera", 0.06, 0.05, false},
                               {"grazing", 0.025, 0.0005, false},  // near: 10 px
                               {"walker_sun_side_35", 0.038, 0.011, false},
                               {"walker_sun_side_70", 0.02, 0.0057, false}};
  for (const scenes::View& v : forest.views) {
    const NearFar r = run_view("forest", forest, oracle, v);
    EXPECT_GE(r.psm.depth.fraction(), 0.995);  // measured >= 99.682% (side 70)
    check(v, r, bounds);
  }
}

}  // namespace
}  // namespace shadow

namespace shadow {
namespace {

// Kozlov 14.1.2, Fig 14-6: the virtual slide-back keeps the near-plane quad and narrows the
// field of view, trading aliasing near the eye for aliasing far away. Measured on the standard
// street overview and the forest walker (PSM 1024^2, 320x180): the median texel footprint in
// pixels (TEXEL_DENSITY, > 1 under-samples) and the misclassified rate per distance band.
TEST(PsmVirtualSlideBack, TradesNearForFar) {
  struct Run {
    const char* label;
    PsmNear near;
    double slide;
  };
  const Run runs[] = {{"receivers", PsmNear::kReceivers, 0},
                      {"virtual default", PsmNear::kVirtualSlideBack, 0},
                      {"virtual 5 m", PsmNear::kVirtualSlideBack, 5},
                      {"virtual 20 m", PsmNear::kVirtualSlideBack, 20}};
  for (auto [scene_name, view_index] : {std::pair{"street", 0}, {"forest", 1}}) {
    const scenes::StandardScene sc =
        std::string(scene_name) == "street" ? scenes::street() : scenes::forest();
    const oracle::RayOracle oracle(*sc.scene);
    const scenes::View& v = sc.views[view_index];
    scenes::Setup s{*sc.scene, v.camera, v.light};
    s.camera.width = 320, s.camera.height = 180;
    std::vector<Measured> ms;
    for (const Run& run : runs) {
      ms.push_back(measure(
          s, oracle, Technique::kPsm, PsmCasters::kInverseProjection, 1024, false,
          [&](RenderRequest& r) {
            r.shadow_map.psm.near = run.near;
            r.shadow_map.psm.virtual_slide = run.slide;
          },
          true));
      const Measured& m = ms.back();
      std::printf(
          "[ vslide   ] %s %s %-16s near %.3g, slide %.3g: footprint median <10 m %.3g, 10-50 m "
          "%.3g, >=50 m %.3g px; misclassified %.3f%% (%s)\n",
          scene_name, v.name.c_str(), run.label, m.fit.virtual_near, m.fit.slide_back,
          m.density_median[0], m.density_median[1], m.density_median[2],
          100 * m.vis.misclassified_rate(), bands(m).c_str());
      EXPECT_EQ(m.vis.nan_mismatch, 0u);
    }
    // Measured (median footprint near / far in px, misclassified with attached shadows):
    //   street overview  receivers 0.896 / 2.49, 0.159%; default (2.96 m) 0.675 / 1.28, 0.065%;
    //                    5 m 0.745 / 1.06, 0.057%; 20 m 1.42 / 0.714, 0.074%
    //   forest walker    receivers 0.789 / 3.43, 0.75%; default (3.56 m) 0.911 / 4.24, 0.99%;
    //                    5 m 0.934 / 4.13, 1.00%; 20 m 1.56 / 1.04, 0.61%
    // Not monotonic for short slides (the light's frustum over the receivers' box changes shape
    // too), but a long slide always moves texels from near to far.
    const Measured &base = ms[0], &far_slide = ms[3];
    EXPECT_GE(far_slide.density_median[0], 1.4 * base.density_median[0]) << scene_name;
    EXPECT_LE(far_slide.density_median[2], 0.35 * base.density_median[2]) << scene_name;
    EXPECT_LE(far_slide.vis.misclassified_rate(), base.vis.misclassified_rate()) << scene_name;
  }
}

// Kozlov 14.3.1: the world-space caster bias P + L (a + b texel(P)) per vertex. On the test
// scene and the street overview, with the NDC slope bias off (constant 2e-5 only), acne (engine
// dark where the oracle is lit) against b = 0, 1, 2, and the cost in missing shadow (engine lit
// where the oracle is dark: peter-panning), beside the default NDC biases.
TEST(PsmWorldBias, TexelScaledBiasRemovesAcne) {
  struct Bias {
    const char* label;
    float constant, slope, b;
  };
  const Bias biases[] = {{"ndc const only", 2e-5f, 0.0f, 0.0f},
                         {"const + b=1", 2e-5f, 0.0f, 1.0f},
                         {"const + b=2", 2e-5f, 0.0f, 2.0f},
                         {"ndc default", 2e-5f, ShadowMapSettings{}.bias_slope, 0.0f},
                         {"default + b=1", 2e-5f, ShadowMapSettings{}.bias_slope, 1.0f}};
  struct Scene_ {
    std::string name;
    scenes::Setup setup;
  };
  std::vector<Scene_> cases;
  for (auto [name, angle] :
       {std::pair{"perpendicular", 90.0}, {"behind_30deg", 30.0}, {"front_60deg", 120.0}}) {
    PsmCase c{name, angle, 600, false, PsmCasters::kInverseProjection, 0, 0};
    cases.push_back({name, setup(c)});
  }
  {
    scenes::StandardScene street = scenes::street();
    scenes::Setup s{*street.scene, street.views[0].camera, street.views[0].light};
    s.camera.width = 320, s.camera.height = 180;
    cases.push_back({"street_overview", s});
  }
  for (const Scene_& c : cases) {
    const oracle::RayOracle oracle(c.setup.scene);
    std::vector<Measured> ms;
    for (const Bias& b : biases) {
      ms.push_back(measure(c.setup, oracle, Technique::kPsm, PsmCasters::kInverseProjection, 1024,
                           false, [&](RenderRequest& r) {
                             r.shadow_map.bias_constant = b.constant;
                             r.shadow_map.bias_slope = b.slope;
                             r.shadow_map.bias_world_texel = b.b;
                           }));
      const Measured& m = ms.back();
      std::printf(
          "[ wbias    ] %-16s %-15s acne %6zu px, missing shadow %6zu px (oracle shadowed "
          "%zu), misclassified %.3f%%\n",
          c.name.c_str(), b.label, m.acne, m.leak, m.shadowed, 100 * m.vis.misclassified_rate());
      EXPECT_EQ(m.vis.nan_mismatch, 0u);
    }
    // Measured: acne 17490 / 13368 / 14967 / 7364 px with the constant alone, 35 / 11 / 16 / 43
    // with b = 1; missing shadow 4 -> 4 / 9 -> 14 / 4 -> 7 / 19 -> 42 px (b = 2: 4 / 14 / 7 /
    // 47). Receivers facing away from the light are dark whatever the bias (attached shadows),
    // so the slope bias no longer leaks light at the terminator. With the default slope bias
    // (0.75 since 2026-11-27; 1.5 before) the NDC biases are as good as b = 1 or better: 0.024 vs
    // 0.119%, 0.079 vs 0.076% (one acne pixel more), 0.061 vs 0.070% on the test scene, 0.111
    // vs 0.157% on the street overview (at 1.5: 0.159%). Before attached shadows b = 1 won.
    EXPECT_LT(ms[1].acne * 20, ms[0].acne) << c.name;
    EXPECT_LT(ms[2].acne * 20, ms[0].acne) << c.name;
    EXPECT_LT(ms[2].leak, 5 * ms[0].leak + 50) << c.name;  // the peter-panning cost stays bounded
    EXPECT_LE(ms[3].vis.misclassified_rate(), 1.05 * ms[1].vis.misclassified_rate()) << c.name;
  }
}

}  // namespace
}  // namespace shadow

namespace shadow {
namespace {

// Spot lights with PSM on the test scene (camera as in PsmOracle, far/near 600, maps 512^2):
// in front of the camera, behind it, in its camera plane, and low over the receivers. Against the
// oracle and against the uniform spot map. (The fallback of a spot among the receivers to the
// uniform spot map is checked as math in psm_fit_test.)
struct SpotCase {
  const char* name;
  glm::vec3 position, target;
  float cone_deg;
  const char* light_case;  // expected start
  double max_misclassified;
  double max_over_uniform;  // PSM - uniform, percentage points / 100
};

class PsmSpot : public ::testing::TestWithParam<SpotCase> {};

TEST_P(PsmSpot, MatchesTheOracle) {
  const SpotCase& c = GetParam();
  PsmCase base{c.name, 45, 600, false, PsmCasters::kInverseProjection, 0, 0};
  scenes::Setup s = setup(base);
  s.light = Light{};
  s.light.type = LightType::kSpot;
  s.light.position = c.position;
  s.light.direction = glm::normalize(c.target - c.position);
  s.light.cone_angle_deg = c.cone_deg;
  const oracle::RayOracle oracle(s.scene);
  const Measured p = measure(s, oracle, Technique::kPsm, PsmCasters::kInverseProjection, 512, true);
  const Measured u =
      measure(s, oracle, Technique::kUniform, PsmCasters::kInverseProjection, 512, false);
  std::printf("[ spot     ] %s: %s\n[ spot     ]   depth: %s\n", c.name, p.light_case.c_str(),
              p.depth.summary().c_str());
  std::printf(
      "[ spot     ]   misclassified psm %.5f%%, uniform %.5f%% (oracle shadowed %zu px), "
      "acne %zu, missing %zu\n",
      100 * p.vis.misclassified_rate(), 100 * u.vis.misclassified_rate(), p.shadowed, p.acne,
      p.leak);
  std::printf("[ spot     ]   by distance psm: %s\n[ spot     ]   uniform: %s\n", bands(p).c_str(),
              bands(u).c_str());
  EXPECT_EQ(p.light_case.rfind(c.light_case, 0), 0u) << p.light_case;
  EXPECT_EQ(p.vis.nan_mismatch, 0u);
  EXPECT_GE(p.depth.fraction(), 0.998);
  EXPECT_LE(p.vis.misclassified_rate(), c.max_misclassified);
  EXPECT_LE(p.vis.misclassified_rate(), u.vis.misclassified_rate() + c.max_over_uniform);
}

INSTANTIATE_TEST_SUITE_P(
    Engine, PsmSpot,
    ::testing::Values(
        // Measured misclassified PSM vs uniform, with attached shadows: 0.079 vs 0.049%, 0.125
        // vs 0.144%, 0.156 vs 0.153%, 0 vs 0%; depth agreement >= 99.884%.
        SpotCase{
            "in_front_overhead", {0, 15, 0}, {0, 0, 0}, 110, "spot from the front", 0.0011, 0.0012},
        SpotCase{"behind_camera", {2, 14, 32}, {0, 0, 0}, 80, "spot from behind", 0.0017, 0.0005},
        SpotCase{
            "camera_plane", {8, 6, 22}, {0, 0, 0}, 90, "spot in the camera plane", 0.002, 0.0005},
        SpotCase{"low_over_receivers",
                 {0, 3, 0},
                 {0, 0, 0.01f},
                 120,
                 "spot from the front",
                 0.0003,
                 0.0002},
        // Inside the receivers' post-perspective box: the uniform spot map, the same 0.0367%.
        SpotCase{"among_receivers",
                 {3, 1.5f, 5},
                 {3, 0, 5.01f},
                 170,
                 "spot from the front: point light, inside or next to the receivers' box: needs a "
                 "cube map; spot: uniform",
                 0.00068,
                 0.0}),
    [](const auto& info) { return std::string(info.param.name); });

// Point lights with PSM (the cases): in the camera plane (directional in
// post-perspective space), just in front of and just behind it, well behind the camera, and
// inside the view frustum, where no single frustum sees every receiver and the fit falls back
// to the cube. Compared with the cube map of the same face size.
struct PointCase {
  const char* name;
  glm::vec3 offset;  // from the eye, along the camera's right, up and forward
  const char* light_case;
  double max_misclassified;
};

class PsmPoint : public ::testing::TestWithParam<PointCase> {};

TEST_P(PsmPoint, MatchesTheOracle) {
  const PointCase& c = GetParam();
  scenes::Setup s = setup(PsmCase{c.name, 45, 600, false, PsmCasters::kInverseProjection, 0, 0});
  const glm::vec3 f = glm::normalize(s.camera.target - s.camera.eye);
  const glm::vec3 right = glm::normalize(glm::cross(f, s.camera.up)), up = glm::cross(right, f);
  s.light = Light{};
  s.light.type = LightType::kPoint;
  s.light.position = s.camera.eye + c.offset.x * right + c.offset.y * up + c.offset.z * f;
  const oracle::RayOracle oracle(s.scene);
  const Measured p = measure(s, oracle, Technique::kPsm, PsmCasters::kInverseProjection, 512, true);
  const Measured q =
      measure(s, oracle, Technique::kCube, PsmCasters::kInverseProjection, 512, false);
  std::printf("[ point    ] %s: %s\n[ point    ]   depth: %s\n", c.name, p.light_case.c_str(),
              p.depth.summary().c_str());
  std::printf("[ point    ]   misclassified psm %.5f%%, cube %.5f%% (oracle shadowed %zu px)\n",
              100 * p.vis.misclassified_rate(), 100 * q.vis.misclassified_rate(), p.shadowed);
  EXPECT_NE(p.light_case.find(c.light_case), std::string::npos) << p.light_case;
  EXPECT_EQ(p.vis.nan_mismatch, 0u);
  if (p.depth.texels > 0) {
    EXPECT_GE(p.depth.fraction(), 0.998);
  }
  EXPECT_LE(p.vis.misclassified_rate(), c.max_misclassified);
}

INSTANTIATE_TEST_SUITE_P(
    Engine, PsmPoint,
    // Measured misclassified PSM vs the cube (512^2 faces), with attached shadows: 0.156 vs
    // 0.150%, 0.162 vs 0.180%, 0.144 vs 0.104%, 0.107 vs 0.110%, and the cube itself in view
    // (0.141%).
    ::testing::Values(PointCase{"camera_plane", {8, 0, 0}, "point in the camera plane", 0.0021},
                      PointCase{"just_in_front", {8, 0, 0.05f}, "point from the front", 0.0022},
                      PointCase{"just_behind", {8, 0, -0.05f}, "point from behind", 0.0019},
                      PointCase{"behind", {3, 8, -10}, "point from behind", 0.0014},
                      PointCase{"in_view", {0, -2, 14}, "needs a cube map: cube", 0.0019}),
    [](const auto& info) { return std::string(info.param.name); });

// PSM's cube-map approach (issue 5): with the light facing the camera, plain PSM's single map
// must cover the whole unit cube seen from a light just beyond it and degrades (Kozlov 14.2);
// the cube faces keep close to the texel size of the light's best angle (perpendicular to the
// view). PSM and uniform get the same texel total as the cube's rendered faces.
TEST(PsmCube, KeepsItsQualityWhenTheLightFacesTheCamera) {
  auto run = [](double angle, Technique t, uint32_t size) {
    scenes::Setup s =
        setup(PsmCase{"cube", angle, 600, false, PsmCasters::kInverseProjection, 0, 0});
    const oracle::RayOracle oracle(s.scene);
    return measure(s, oracle, t, PsmCasters::kInverseProjection, size, t != Technique::kPsmCube, {},
                   true);
  };
  const Measured best = run(90, Technique::kPsm, 512);
  for (double angle : {150.0, 170.0, 178.0}) {
    const Measured cube = run(angle, Technique::kPsmCube, 512);
    size_t faces = 0;
    for (const CubeFaceReport& f : cube.fit.cube_faces) faces += f.rendered;
    const uint32_t equal = uint32_t(std::lround(512 * std::sqrt(double(faces))));
    const Measured psm = run(angle, Technique::kPsm, equal);
    const Measured uniform = run(angle, Technique::kUniform, equal);
    std::printf(
        "[ psm cube ] %.0f deg, %zu faces of 512^2 vs %u^2: median texel footprint (px) <10 m / "
        "10-50 m: psm_cube %.3f / %.3f, psm %.3f / %.3f, uniform %.3f / %.3f; psm 512^2 at 90 "
        "deg %.3f / %.3f; texels %.2e..%.2e of the cube's edge\n",
        angle, faces, equal, cube.density_median[0], cube.density_median[1], psm.density_median[0],
        psm.density_median[1], uniform.density_median[0], uniform.density_median[1],
        best.density_median[0], best.density_median[1], cube.fit.cube_texel_min,
        cube.fit.cube_texel_max);
    std::printf("[ psm cube ]   misclassified psm_cube %.4f%%, psm %.4f%%, uniform %.4f%%\n",
                100 * cube.vis.misclassified_rate(), 100 * psm.vis.misclassified_rate(),
                100 * uniform.vis.misclassified_rate());
    EXPECT_NE(cube.light_case.find("cube faces on 5 sides"), std::string::npos) << cube.light_case;
    EXPECT_EQ(cube.vis.nan_mismatch, 0u);
    for (int band : {0, 1}) {
      // Measured: at most 2.9x the best angle's footprint (170 deg, < 10 m), and 0.51-0.69 of
      // PSM's at the same texel total. (Uniform at that total is finer still at 170 and 178
      // deg on this scene, 0.48-0.65 of the cube's; reported, not asserted.)
      EXPECT_LE(cube.density_median[band], 3.2 * best.density_median[band]) << angle;
      EXPECT_LE(cube.density_median[band], 0.75 * psm.density_median[band]) << angle;
    }
    EXPECT_LE(cube.vis.misclassified_rate(), psm.vis.misclassified_rate()) << angle;
  }
}

// PSM_CUBE against the oracle: every face's depth through its own matrix, and visibility with
// the hard test and the filters that cross the faces' seams (their guard bands), for the light
// facing the camera (a point light beyond the unit cube) and from behind with casters behind
// the camera (the inverted light, depth through infinity).
TEST(PsmCube, EveryFaceAgreesWithTheOracle) {
  struct Case {
    double angle;
    bool wall;
    double min_depth_agree, max_misclassified;
  };
  // Measured: depth >= 99.99% of texels within 1e-5 on every face; misclassified with attached
  // shadows 0 facing (32638 of 32732 pixels shadowed: the light travels upward and every seen
  // pixel faces away from it, so there visibility only tests that rule), 0.015-0.034% behind
  // with the wall (21188 shadowed).
  for (const Case& c : {Case{178, false, 0.9995, 0.00031}, Case{45, true, 0.9995, 0.00065}}) {
    const scenes::Setup s =
        setup(PsmCase{"cube", c.angle, 600, c.wall, PsmCasters::kInverseProjection, 0, 0});
    const oracle::RayOracle oracle(s.scene);
    RenderRequest req;
    req.scene = std::make_shared<Scene>(s.scene);
    req.camera = s.camera;
    req.lights = {s.light};
    req.shadow_map.size = 512;
    req.shadow_map.technique = Technique::kPsmCube;
    req.products = {Product::kShadowMap};
    const RenderResult r = engine().render(req);
    const Texture& cube = texture(r, Product::kShadowMap);
    ASSERT_GE(cube.faces, 3u) << r.light_fits[0].light_case;
    oracle::DepthOptions positive_w;
    positive_w.require_positive_w = true;
    for (uint32_t k = 0; k < cube.faces; ++k) {
      const std::span<const float> face(cube.data.data() + size_t{k} * 512 * 512, 512 * 512);
      const auto expected =
          oracle.shadow_map_depth(glm::dmat4(cube.cube_faces[k].world_to_ndc), 512, positive_w);
      const auto a = oracle::compare_depth(face, expected, 1e-5);
      std::printf("[ psm cube ] %.0f deg face %s: %s\n", c.angle, cube.cube_faces[k].name.c_str(),
                  a.summary().c_str());
      EXPECT_GE(a.fraction(), c.min_depth_agree) << cube.cube_faces[k].name;
    }
    for (FilterKind filter : {FilterKind::kHard, FilterKind::kPcf2x2, FilterKind::kPoisson}) {
      const Measured m = measure(s, oracle, Technique::kPsmCube, PsmCasters::kInverseProjection,
                                 512, false, [&](RenderRequest& q) { q.filter.kind = filter; });
      std::printf(
          "[ psm cube ] %.0f deg filter %d: misclassified %.4f%% (oracle shadowed %zu of %zu)\n",
          c.angle, int(filter), 100 * m.vis.misclassified_rate(), m.shadowed, m.vis.both_valid);
      EXPECT_EQ(m.vis.nan_mismatch, 0u);
      EXPECT_LE(m.vis.misclassified_rate(), c.max_misclassified) << int(filter);
    }
  }
}

// PSM_CUBE with a point light inside a room that is one caster box (the standard room's three
// views): the box holds the light, so it may hold geometry anywhere near it, and the faces'
// near planes come from the light's measured nearest caster. Clipped at 1e-4 of the receivers'
// depth instead, the stored depth spanned ~1e-4 over the room and the constant bias lit
// receivers up to ~20% of their distance behind a caster (the leaning slab's shadow on the
// wall behind it and on the floor under it), a floor of 0.27% at the centre light at every map
// size. Measured at 1024^2 faces, with attached shadows (before: 0.303%, 0.070%, 0.087%).
TEST(PsmCube, PointLightInsideACasterBox) {
  struct Case {
    const char* view;
    double max_misclassified;
  };
  const scenes::StandardScene room = scenes::room();
  // Measured 0.0304%, 0.0404%, 0.0312% (slope bias 0.75; 0.0304, 0.0412, 0.0286% at 1.5).
  for (const Case& c : {Case{"point_centre", 0.00040}, Case{"point_near_wall", 0.00054},
                        Case{"point_low", 0.00038}}) {
    const scenes::View& view = scenes::find_view(room, c.view);
    scenes::Setup s{*room.scene, view.camera, view.light};
    s.light.size = 0.0f;
    const oracle::RayOracle oracle(s.scene);
    const Measured m =
        measure(s, oracle, Technique::kPsmCube, PsmCasters::kInverseProjection, 1024, false);
    std::printf("[ psm cube ] room %s: %s; misclassified %.4f%% (engine lit, oracle dark %zu)\n",
                c.view, m.light_case.c_str(), 100 * m.vis.misclassified_rate(), m.leak);
    EXPECT_NE(m.light_case.find("cube faces on 6 sides"), std::string::npos) << m.light_case;
    EXPECT_EQ(m.vis.nan_mismatch, 0u);
    EXPECT_LE(m.vis.misclassified_rate(), c.max_misclassified) << c.view;
  }
}

// PSM_CUBE at the extremes: far/near up to 10^6 (Q -> 1: the post-perspective light hugs the
// unit cube) with the light facing the camera, along the view from behind, and perpendicular
// to it (one orthographic map). measure() checks every matrix and texel is finite.
TEST(PsmCube, StaysFiniteAtTheExtremes) {
  for (double far_over_near : {10.0, 1e3, 1e6})
    for (double angle : {180.0, 178.0, 90.0, 0.0}) {
      const scenes::Setup s = setup(
          PsmCase{"extreme", angle, far_over_near, false, PsmCasters::kInverseProjection, 0, 0});
      const oracle::RayOracle oracle(s.scene);
      const Measured m =
          measure(s, oracle, Technique::kPsmCube, PsmCasters::kInverseProjection, 256, false);
      std::printf("[ psm cube ] far/near %.0e, %.0f deg: %s; misclassified %.4f%%\n", far_over_near,
                  angle, m.light_case.c_str(), 100 * m.vis.misclassified_rate());
      EXPECT_EQ(m.vis.nan_mismatch, 0u);
      // Measured with attached shadows at most 0.32% with the cube (256^2 faces; far/near 1e6
      // along the view, where LiSPSM's and the uniform map miss as many) and 0.30% with the one
      // 256^2 map at 90 deg; a broken face shows as a whole region wrong.
      EXPECT_LE(m.vis.misclassified_rate(), angle == 90.0 ? 0.0039 : 0.0037)
          << far_over_near << " " << angle;
    }
}

}  // namespace
}  // namespace shadow
