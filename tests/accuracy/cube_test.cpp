// Omnidirectional point-light cube maps (issue 5) against the Embree oracle: every rendered
// face's depth through its own matrix, and visibility per pixel, split into the pixels at a
// face seam (a 4-neighbour belongs to another face) and the rest. Bounds are the measured
// figures with a small margin; every run prints the measured values.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "engine/engine.hpp"
#include "engine/light/cube_fit.hpp"
#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/scenes.hpp"
#include "oracle/standard_scenes.hpp"
#include "shared_engine.hpp"

namespace shadow {
namespace {

using accuracy::engine;
using accuracy::texture;

// The standard room (tests/oracle/standard_scenes.hpp) under its point light off the centre:
// the cube's seams run across the floor, the walls and the ceiling, and shadow edges cross them.
scenes::Setup room() {
  const scenes::StandardScene room = scenes::room();
  const scenes::View& view = room.views[0];
  scenes::Setup s{*room.scene, view.camera, view.light};
  s.light.size = 0.0f;
  return s;
}

RenderRequest request(const scenes::Setup& s, uint32_t size, std::vector<Product> products) {
  RenderRequest r;
  r.scene = std::make_shared<Scene>(s.scene);
  r.camera = s.camera;
  r.lights = {s.light};
  r.shadow_map.size = size;
  r.shadow_map.technique = Technique::kCube;
  r.products = std::move(products);
  return r;
}

TEST(CubeDepth, EveryFaceAgreesWithRayTracedDepth) {
  const scenes::Setup s = room();
  const oracle::RayOracle oracle(s.scene);
  for (uint32_t size : {512u, 1024u}) {
    const RenderResult r = engine().render(request(s, size, {Product::kShadowMap}));
    const Texture& cube = texture(r, Product::kShadowMap);
    ASSERT_EQ(cube.faces, 6u) << "the room surrounds the light: every face has casters";
    ASSERT_EQ(cube.cube_faces.size(), 6u);
    ASSERT_EQ(cube.data.size(), size_t{6} * size * size);
    for (uint32_t k = 0; k < 6; ++k) {
      EXPECT_EQ(cube.cube_faces[k].name, kCubeFaceNames[k]);
      const std::span<const float> face(cube.data.data() + size_t{k} * size * size,
                                        size_t{size} * size);
      oracle::DepthOptions positive_w;
      positive_w.require_positive_w = true;
      const auto expected =
          oracle.shadow_map_depth(glm::dmat4(cube.cube_faces[k].world_to_ndc), size, positive_w);
      const auto a = oracle::compare_depth(face, expected, 1e-5);
      std::printf("[ cube     ] face %s %u^2: %s\n", kCubeFaceNames[k], size, a.summary().c_str());
      // Within 1e-5: the foundation's bar for every map. The misses are on the box 0.5 m from
      // the light, whose faces are steep in NDC depth (1e-5 is < 0.01 texel of their slope, the
      // order of the 1/256-texel snapping); within 1e-4 only silhouette texels remain.
      const auto loose = oracle::compare_depth(face, expected, 1e-4);
      std::printf("[ cube     ] face %s %u^2 within 1e-4: %.5f%%\n", kCubeFaceNames[k], size,
                  100.0 * loose.fraction());
      EXPECT_GE(a.fraction(), 0.995) << kCubeFaceNames[k];
      EXPECT_GE(loose.fraction(), 0.99999) << kCubeFaceNames[k];
    }
  }
}

struct SeamSplit {
  oracle::VisibilityError seam, inner;
};

// Visibility against the oracle's shadow rays, split at the face seams.
SeamSplit visibility_error(const scenes::Setup& s, const RenderRequest& req) {
  const RenderResult r = engine().render(req);
  const Texture& vis = texture(r, Product::kVisibility);
  const Texture& pos = texture(r, Product::kPosition);
  const auto reference = oracle::RayOracle(s.scene).camera_visibility(s.camera, s.light);
  const uint32_t w = s.camera.width, h = s.camera.height;
  const glm::dvec3 light(s.light.position);
  std::vector<int> face(size_t{w} * h, -1);
  for (size_t i = 0; i < face.size(); ++i) {
    const glm::dvec3 p(pos.data[3 * i], pos.data[3 * i + 1], pos.data[3 * i + 2]);
    if (!std::isnan(p.x)) face[i] = cube_face(p - light);
  }
  std::vector<float> seam_e, seam_r, inner_e, inner_r;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t i = size_t{y} * w + x;
      bool seam = false;
      if (x > 0) seam |= face[i - 1] != face[i] && face[i - 1] >= 0;
      if (x + 1 < w) seam |= face[i + 1] != face[i] && face[i + 1] >= 0;
      if (y > 0) seam |= face[i - w] != face[i] && face[i - w] >= 0;
      if (y + 1 < h) seam |= face[i + w] != face[i] && face[i + w] >= 0;
      (seam ? seam_e : inner_e).push_back(vis.data[i]);
      (seam ? seam_r : inner_r).push_back(reference[i]);
    }
  return {oracle::compare_visibility(seam_e, seam_r), oracle::compare_visibility(inner_e, inner_r)};
}

TEST(CubeVisibility, AgreesWithShadowRaysAcrossSeams) {
  const scenes::Setup s = room();
  struct Case {
    const char* name;
    FilterKind kind;
    double inner_bound, seam_bound;
  };
  // Measured with attached shadows against Embree with a 1e-6 ray offset: 0.019 / 0.017 /
  // 0.011% elsewhere (of 226792 pixels), 0 of 3608 seam pixels, for the first three. CSM (a
  // basis per face): 0.023% elsewhere, 0 of 3608 seam pixels.
  for (const Case& c : {Case{"hard", FilterKind::kHard, 2.5e-4, 1e-3},
                        Case{"pcf2x2", FilterKind::kPcf2x2, 2.3e-4, 1e-3},
                        Case{"poisson r3", FilterKind::kPoisson, 1.6e-4, 1e-3},
                        Case{"csm M16 w1", FilterKind::kCsm, 3.1e-4, 2.8e-3}}) {
    RenderRequest req = request(s, 2048, {Product::kVisibility, Product::kPosition});
    req.filter.kind = c.kind;
    req.filter.poisson.radius = 3.0f;
    req.filter.csm.terms = 16;  // a basis per face, each looked up over one texel
    req.filter.csm.window = 1.0f;
    const SeamSplit e = visibility_error(s, req);
    std::printf("[ cube vis ] %s: seams %s\n[ cube vis ] %s: elsewhere %s\n", c.name,
                e.seam.summary().c_str(), c.name, e.inner.summary().c_str());
    EXPECT_GT(e.seam.both_valid, 1000u) << "the view crosses seams";
    EXPECT_EQ(e.seam.nan_mismatch + e.inner.nan_mismatch, 0u);
    EXPECT_LE(e.inner.misclassified_rate(), c.inner_bound) << c.name;
    EXPECT_LE(e.seam.misclassified_rate(), c.seam_bound) << c.name;
  }
}

}  // namespace
}  // namespace shadow
