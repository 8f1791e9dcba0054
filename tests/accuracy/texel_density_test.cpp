// The texel-density kernel (PRODUCT_TEXEL_DENSITY) against the double-precision reference at
// the oracle's camera hits, for an orthographic (sun) and a perspective (spot) map, and a point
// light's cube (each pixel through the face that decides it).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include <gtest/gtest.h>

#include "engine/engine.hpp"
#include "oracle/scenes.hpp"
#include "oracle/texel_density.hpp"
#include "shared_engine.hpp"

namespace shadow {
namespace {

using accuracy::engine;

struct Case {
  const char* name;
  bool spot;
  // Fraction of pixels seen by both within 1e-3 relative: all but 2 silhouette pixels each.
  double min_agree;
};

class TexelDensity : public ::testing::TestWithParam<Case> {};

// The setup's view of its light: the shadow map (size^2, or a cube's faces) and texel density.
RenderResult render_density(const scenes::Setup& s, uint32_t size) {
  RenderRequest req;
  req.scene = std::make_shared<Scene>(s.scene);
  req.camera = s.camera;
  req.lights = {s.light};
  req.shadow_map.size = size;
  req.products = {Product::kShadowMap, Product::kTexelDensity};
  return engine().render(req);
}

TEST_P(TexelDensity, MatchesDoublePrecisionReference) {
  scenes::Setup s = scenes::test_scene();
  if (GetParam().spot) {
    s.light.type = LightType::kSpot;
    s.light.position = {6, 14, 10};
    s.light.direction = -s.light.position;
    s.light.cone_angle_deg = 70;
  }
  const RenderResult r = render_density(s, 2048);
  ASSERT_EQ(r.textures.size(), 2u);
  const Texture& map = r.textures[0];
  const Texture& density = r.textures[1];
  EXPECT_EQ(density.name, "texel_density");
  ASSERT_EQ(density.data.size(), size_t{s.camera.width} * s.camera.height);

  const oracle::RayOracle oracle(s.scene);
  const oracle::CameraHits hits = oracle.cast_camera(s.camera);
  const std::vector<double> ref = oracle::texel_density(
      hits, glm::dmat4(map.world_to_ndc), map.width, glm::dmat4(density.world_to_ndc));
  size_t both = 0, agree = 0, nan_mismatch = 0;
  double worst = 0.0;
  for (size_t i = 0; i < ref.size(); ++i) {
    const double e = density.data[i];
    if (std::isnan(e) != std::isnan(ref[i])) ++nan_mismatch;
    if (std::isnan(e) || std::isnan(ref[i])) continue;
    ++both;
    const double rel = std::abs(e - ref[i]) / ref[i];
    worst = std::max(worst, rel);
    agree += rel <= 1e-3;
  }
  std::vector<float> ref_f(ref.begin(), ref.end());
  std::printf(
      "engine    %s\nreference %s\n%zu of %zu within 1e-3 relative (worst %.3g), %zu NaN "
      "mismatches\n",
      oracle::density_stats(density.data).summary().c_str(),
      oracle::density_stats(ref_f).summary().c_str(), agree, both, worst, nan_mismatch);
  EXPECT_GT(both, ref.size() / 8);  // measured: 491472 (sun), 158917 (spot) of 921600
  EXPECT_GE(static_cast<double>(agree) / both, GetParam().min_agree);
  // Silhouette pixels and the map's border may differ; measured 0 of each.
  EXPECT_LT(nan_mismatch, ref.size() / 1000);
}

// A point light's cube, in one launch: each pixel's footprint is the one through the face that
// decides it, so it must equal the reference through one of the rendered faces.
TEST(TexelDensityCube, EachPixelMatchesTheReferenceThroughOneRenderedFace) {
  scenes::Setup s = scenes::test_scene();
  s.light.type = LightType::kPoint;
  s.light.position = {2, 9, 3};
  const RenderResult r = render_density(s, 1024);
  ASSERT_EQ(r.textures.size(), 2u);
  const Texture& cube = r.textures[0];
  const Texture& density = r.textures[1];
  ASSERT_GE(cube.cube_faces.size(), 2u);  // pixels decided by several faces
  const oracle::RayOracle oracle(s.scene);
  const oracle::CameraHits hits = oracle.cast_camera(s.camera);
  std::vector<std::vector<double>> refs;
  for (const TextureFace& f : cube.cube_faces)
    refs.push_back(oracle::texel_density(hits, glm::dmat4(f.world_to_ndc), cube.width,
                                         glm::dmat4(density.world_to_ndc)));
  size_t seen = 0, agree = 0;
  std::vector<size_t> per_face(refs.size(), 0);
  for (size_t i = 0; i < density.data.size(); ++i) {
    const double e = density.data[i];
    if (std::isnan(e)) continue;
    ++seen;
    for (size_t k = 0; k < refs.size(); ++k)
      if (std::abs(e - refs[k][i]) <= 1e-3 * refs[k][i]) {
        ++agree, ++per_face[k];
        break;
      }
  }
  std::printf("%zu of %zu pixels within 1e-3 of a face's reference; per face:", agree, seen);
  for (size_t n : per_face) std::printf(" %zu", n);
  std::printf("\n");
  EXPECT_GT(seen, density.data.size() / 8);
  EXPECT_GE(static_cast<double>(agree) / seen, 0.9999);
  EXPECT_GE(std::count_if(per_face.begin(), per_face.end(), [](size_t n) { return n > 1000; }),
            2);  // the launch really reads several faces
}

INSTANTIATE_TEST_SUITE_P(Lights, TexelDensity,
                         ::testing::Values(Case{"sun", false, 0.9999}, Case{"spot", true, 0.9999}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace shadow
