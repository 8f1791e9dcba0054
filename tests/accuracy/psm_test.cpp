// Perspective Shadow Maps against the Embree oracle at the configurations issue 4 lists: the
// map's depth through its own matrix, visibility against shadow rays from the engine's surface
// points, and no NaN/Inf anywhere. Bounds are the measured figures with a margin; every run
// prints the measured values. PSM_DEBUG=1 splits the misses (dark vs lit, within 15 m of the eye);
// PSM_SLOPE / PSM_CONST override the biases (to tell bias from fit problems).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/engine.hpp"
#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/scenes.hpp"
#include "oracle/standard_scenes.hpp"

namespace shadow {
namespace {

Engine& engine() {
  static Engine e;
  return e;
}

const Texture& texture(const RenderResult& r, Product kind) {
  auto it = std::find_if(r.textures.begin(), r.textures.end(),
                         [&](const Texture& t) { return t.kind == kind; });
  if (it == r.textures.end()) throw std::runtime_error("product missing from the result");
  return *it;
}

struct PsmCase {
  std::string name;
  double angle_deg;  // light's travel vs the view direction: 0 = along it (from behind)
  double far_over_near = 600;
  bool behind_wall = false;  // a wall behind the camera whose shadow falls into view
  PsmCasters casters = PsmCasters::kInverseProjection;
  double min_depth_agree;  // fraction of texels within 1e-5 NDC of the oracle
  double max_misclassified;
};

// The test scene seen from low over its edge (a street-like view), far = 60.
scenes::Setup setup(const PsmCase& c) {
  scenes::Setup s = scenes::test_scene();
  s.camera.eye = {0, 6, 22};
  s.camera.target = {0, 0, 0};
  s.camera.width = 320;
  s.camera.height = 180;
  s.camera.far = 60;
  s.camera.near = float(60 / c.far_over_near);
  const glm::dvec3 f = glm::normalize(glm::dvec3(s.camera.target - s.camera.eye));
  // Rotate the view direction by the angle towards "down and to the side", so that the light
  // still reaches the ground at mid angles.
  const glm::dvec3 side =
      glm::normalize(glm::dvec3(0.4, -1, 0) - glm::dot(glm::dvec3(0.4, -1, 0), f) * f);
  const double a = glm::radians(c.angle_deg);
  s.light.direction = glm::vec3(glm::normalize(std::cos(a) * f + std::sin(a) * side));
  if (c.behind_wall)  // 60 m wide, 30 m high, 6 m behind the camera: its shadow reaches z ~ 5
    scenes::add(s.scene, scenes::box_mesh(), scenes::trs({0, 15, 28}, 0, {0, 1, 0}, {60, 30, 1}));
  return s;
}

struct Measured {
  oracle::DepthAgreement depth;
  oracle::VisibilityError vis;
  std::string light_case;
  size_t shadowed = 0;  // oracle pixels in shadow
};

Measured measure(const scenes::Setup& s, const oracle::RayOracle& oracle, Technique technique,
                 PsmCasters casters, uint32_t map_size, bool with_depth) {
  RenderRequest req;
  req.scene = std::make_shared<Scene>(s.scene);
  req.camera = s.camera;
  req.light = s.light;
  req.shadow_map.size = map_size;
  req.shadow_map.technique = technique;
  req.shadow_map.psm.casters = casters;
  if (const char* b = std::getenv("PSM_SLOPE")) req.shadow_map.bias_slope = std::atof(b);
  if (const char* b = std::getenv("PSM_CONST")) req.shadow_map.bias_constant = std::atof(b);
  req.products = {Product::kShadowMap, Product::kVisibility, Product::kPosition};
  const RenderResult r = engine().render(req);
  const Texture& map = texture(r, Product::kShadowMap);
  const Texture& vis = texture(r, Product::kVisibility);
  const Texture& pos = texture(r, Product::kPosition);
  Measured m;
  m.light_case = r.light_fit.light_case;
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < 4; ++k) EXPECT_TRUE(std::isfinite(map.world_to_ndc[c][k]));
  for (float v : map.data) EXPECT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 1.0f) << v;
  for (double v : {r.light_fit.virtual_near, r.light_fit.virtual_far, r.light_fit.light_near,
                   r.light_fit.light_far, r.light_fit.slide_back})
    EXPECT_TRUE(std::isfinite(v));
  if (with_depth) {
    // The rasterizer draws only clip w > 0, which is where every caster of a visible receiver
    // is (the fit makes it so); the whole line's other half (w < 0) is not part of the map.
    oracle::DepthOptions o;
    o.require_positive_w = true;
    const auto expected = oracle.shadow_map_depth(glm::dmat4(map.world_to_ndc), map_size, o);
    m.depth = oracle::compare_depth(map.data, expected, 1e-5);
  }
  const oracle::CameraHits hits = oracle.cast_camera(s.camera);
  std::vector<glm::dvec3> points(hits.size()), normals(hits.size());
  std::vector<uint8_t> receives(hits.size(), 1);
  for (size_t i = 0; i < hits.size(); ++i) {
    points[i] = glm::dvec3(pos.data[3 * i], pos.data[3 * i + 1], pos.data[3 * i + 2]);
    normals[i] = hits.normal[i];
    if (hits.hit(i)) receives[i] = s.scene.instances[hits.instance[i]].receives_shadows;
  }
  const auto expected = oracle.hard_visibility(s.light, points, normals, receives);
  for (float v : expected) m.shadowed += v < 0.5f;
  m.vis = oracle::compare_visibility(vis.data, expected);
  if (std::getenv("PSM_DEBUG")) {
    size_t acne = 0, leak = 0, near_miss = 0;
    for (size_t i = 0; i < expected.size(); ++i) {
      if (std::isnan(expected[i]) || std::isnan(vis.data[i])) continue;
      near_miss += (vis.data[i] < 0.5f) != (expected[i] < 0.5f) &&
                   glm::length(points[i] - glm::dvec3(s.camera.eye)) < 15.0;
      acne += vis.data[i] < 0.5f && expected[i] > 0.5f;
      leak += vis.data[i] > 0.5f && expected[i] < 0.5f;
    }
    std::printf(
        "[ debug    ] engine dark/oracle lit %zu, engine lit/oracle dark %zu, within 15 m %zu\n",
        acne, leak, near_miss);
  }
  return m;
}

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
  EXPECT_EQ(p.vis.nan_mismatch, 0u);
  EXPECT_GE(p.depth.fraction(), c.min_depth_agree);
  EXPECT_LE(p.vis.misclassified_rate(), c.max_misclassified);
  // PSM against uniform at the same map size. Light along the view (both signs) must degrade
  // gracefully: measured +0.116 (behind) and +0.040 (front) percentage points at 512^2.
  if (c.angle_deg == 0 || c.angle_deg == 180) {
    EXPECT_LE(p.vis.misclassified_rate(), u.vis.misclassified_rate() + 0.0015);
  }
  if (c.behind_wall) {
    EXPECT_GT(p.shadowed, 20000u);  // the wall's shadow is in view
  }
}

INSTANTIATE_TEST_SUITE_P(
    Engine, PsmOracle,
    ::testing::Values(
        PsmCase{"perpendicular", 90, 600, false, PsmCasters::kInverseProjection, 0.995, 0.013},
        PsmCase{"behind_1deg", 1, 600, false, PsmCasters::kInverseProjection, 0.995, 0.004},
        PsmCase{"behind_5deg", 5, 600, false, PsmCasters::kInverseProjection, 0.995, 0.0035},
        PsmCase{"behind_30deg", 30, 600, false, PsmCasters::kInverseProjection, 0.995, 0.003},
        PsmCase{"behind_60deg", 60, 600, false, PsmCasters::kInverseProjection, 0.995, 0.0022},
        PsmCase{"front_1deg", 179, 600, false, PsmCasters::kInverseProjection, 0.995, 0.0055},
        PsmCase{"front_5deg", 175, 600, false, PsmCasters::kInverseProjection, 0.995, 0.006},
        PsmCase{"front_30deg", 150, 600, false, PsmCasters::kInverseProjection, 0.995, 0.028},
        PsmCase{"front_60deg", 120, 600, false, PsmCasters::kInverseProjection, 0.995, 0.012},
        PsmCase{"along_view", 0, 600, false, PsmCasters::kInverseProjection, 0.995, 0.003},
        PsmCase{"against_view", 180, 600, false, PsmCasters::kInverseProjection, 0.995, 0.005},
        PsmCase{"grazing_behind_89deg", 89, 600, false, PsmCasters::kInverseProjection, 0.995,
                0.0135},
        PsmCase{"grazing_behind_89_99deg", 89.99, 600, false, PsmCasters::kInverseProjection, 0.995,
                0.013},
        PsmCase{"ratio_10", 60, 10, false, PsmCasters::kInverseProjection, 0.995, 0.0022},
        PsmCase{"ratio_1e3", 60, 1e3, false, PsmCasters::kInverseProjection, 0.995, 0.0022},
        PsmCase{"ratio_1e5", 60, 1e5, false, PsmCasters::kInverseProjection, 0.995, 0.0023},
        PsmCase{"ratio_1e6", 60, 1e6, false, PsmCasters::kInverseProjection, 0.995, 0.004},
        PsmCase{"wall_behind_inverse", 45, 600, true, PsmCasters::kInverseProjection, 0.995,
                0.0026},
        PsmCase{"wall_behind_slide_back", 45, 600, true, PsmCasters::kSlideBack, 0.995, 0.0024}),
    [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace shadow

namespace shadow {
namespace {

// The standard street (1.5 km, eye at 1.7 m, far/near 2e4) under each of its suns.
TEST(PsmStreet, EveryViewAgainstShadowRays) {
  const scenes::StandardScene street = scenes::street();
  const oracle::RayOracle oracle(*street.scene);
  for (const scenes::View& v : street.views) {
    if (v.light.type != LightType::kDirectional) continue;
    scenes::Setup s{*street.scene, v.camera, v.light};
    s.camera.width = 320, s.camera.height = 180;
    const Measured p =
        measure(s, oracle, Technique::kPsm, PsmCasters::kInverseProjection,
                std::getenv("PSM_SIZE") ? std::atoi(std::getenv("PSM_SIZE")) : 1024, true);
    const Measured u =
        measure(s, oracle, Technique::kUniform, PsmCasters::kInverseProjection, 1024, false);
    std::printf(
        "[ street   ] %s: %s; depth %s\n[ street   ]   misclassified psm %.4f%%, "
        "uniform %.4f%%\n",
        v.name.c_str(), p.light_case.c_str(), p.depth.summary().c_str(),
        100 * p.vis.misclassified_rate(), 100 * u.vis.misclassified_rate());
    // Measured at 1024^2, 320x180: overview 1.12% (uniform 1.40%), light behind the camera 3.20%
    // (0.08%), facing it 4.16% (0.57%), grazing 7.59% (1.46%). Sampling, not bias: zero biases
    // or a receiver-side world-space bias leave them; PSM_SIZE=4096 gives 0.90/0.19/0.88/3.8%.
    // With the sun near the view direction the post-perspective light sits near the view centre
    // and its frustum over the whole receiver box spends few texels where these misses are.
    // The bounds only guard against regressions.
    const double bound = v.name == "overview"              ? 0.013
                         : v.name == "light_behind_camera" ? 0.037
                         : v.name == "light_facing_camera" ? 0.048
                                                           : 0.087;
    EXPECT_GE(p.depth.fraction(), 0.97);  // measured >= 97.43% (overview: fine facade detail)
    EXPECT_EQ(p.vis.nan_mismatch, 0u);
    EXPECT_LE(p.vis.misclassified_rate(), bound) << v.name;
  }
}

}  // namespace
}  // namespace shadow
