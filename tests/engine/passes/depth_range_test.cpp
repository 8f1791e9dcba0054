// The PSM near-plane reduction (kernels/depth_range.cl) against a double-precision reduction over
// the same G-buffer, and the engine feeding it to the PSM fit: with psm_near = RECEIVERS the
// virtual near plane sits at the nearest receiving pixel, not at the bounding boxes' nearest point.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "engine/engine.hpp"
#include "engine/passes/depth_range.hpp"
#include "engine/passes/pcf.hpp"
#include "engine/passes/shadow_test.hpp"
#include "occluder_scene.hpp"

namespace shadow {
namespace {

struct Reference {
  double min = INFINITY, max = -INFINITY;
};

Reference reduce(const std::vector<float>& pos, const std::vector<float>& nrm, const Camera& cam) {
  const glm::dvec3 eye(cam.eye), fwd = glm::normalize(glm::dvec3(cam.target) - eye);
  Reference r;
  for (size_t p = 0; p < pos.size() / 3; ++p) {
    const glm::dvec3 x(pos[3 * p], pos[3 * p + 1], pos[3 * p + 2]);
    if (std::isnan(x.x) || std::isnan(x.y) || std::isnan(x.z) || nrm[4 * p + 3] == 0.0f) continue;
    const double d = glm::dot(x - eye, fwd);
    r.min = std::min(r.min, d), r.max = std::max(r.max, d);
  }
  return r;
}

// A w x h camera far from the origin, as on the street, and a G-buffer of random points up to
// 400 m around its eye: about a fifth not receiving shadows, a twentieth not seen (NaN); normals
// along +z. A non-receiver is nearest and farthest of all: it must not count.
struct RandomView {
  Camera cam;
  std::vector<float> pos, nrm;
  GBuffer g;
  RandomView(cl::Runtime& runtime, uint32_t w, uint32_t h, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    cam.eye = {1200.5f, 1.7f, -830.25f};
    cam.target = {1150.0f, 0.0f, -900.0f};
    cam.width = w, cam.height = h;
    const uint32_t pixels = w * h;
    pos.resize(size_t{pixels} * 3), nrm.resize(size_t{pixels} * 4);
    for (uint32_t p = 0; p < pixels; ++p) {
      const float s = 1.0f + 400.0f * (0.5f + 0.5f * u(rng));
      for (int k = 0; k < 3; ++k) pos[3 * p + k] = cam.eye[k] + s * u(rng);
      const float r = u(rng);
      nrm[4 * p + 2] = 1.0f;
      nrm[4 * p + 3] = r < -0.6f ? 0.0f : (r < 0.6f ? 1.0f : 3.0f);  // none, depth test, class 1
      if (r > 0.9f) pos[3 * p + 1] = NAN;                            // the camera sees nothing
    }
    pos[0] = cam.eye.x + 0.01f, nrm[3] = 0.0f;
    g.position = runtime.upload(pos);
    g.normal = runtime.upload(nrm);
    runtime.finish();  // the uploads read the vectors asynchronously
  }
};

TEST(DepthRange, KernelMatchesTheDoubleReduction) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  DepthRangePass pass(runtime, kernels);
  std::mt19937 rng(7);
  double worst = 0;
  // Sizes around the chunk (4096 pixels): one partial, a ragged last chunk, 1080p.
  for (auto [w, h] : {std::pair{64u, 64u}, {333u, 77u}, {1920u, 1080u}}) {
    const RandomView v(runtime, w, h, rng);
    const Camera& cam = v.cam;
    Timeline t;
    const std::optional<DepthRange> got = pass.run(v.g, cam, t);
    const Reference want = reduce(v.pos, v.nrm, cam);
    ASSERT_TRUE(got.has_value());
    const double scale = glm::length(glm::dvec3(cam.eye)) + want.max;
    const double err = std::max(std::abs(got->min - want.min), std::abs(got->max - want.max));
    worst = std::max(worst, err / scale);
    std::printf("[ depth    ] %ux%u: min %.9g (ref %.9g), max %.9g (ref %.9g), %.3f ms device\n", w,
                h, got->min, want.min, got->max, want.max, t.timings().at(0).device_ms);
  }
  std::printf("[ depth    ] worst error / (|eye| + max depth) %.3g\n", worst);
  EXPECT_LT(worst, 5e-8);  // measured 1.8e-8: float dot product of float positions
}

// A quality probe's hard test measures the range as it tests (pcf.cl, VIEW_DEPTH): the same bits
// as the pass, on images of one strip, fewer pixels than a strip, ragged and 640x360; and the
// same visibility as the test without it.
TEST(DepthRange, TheHardTestsPartialsGiveThePassesBits) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  DepthRangePass pass(runtime, kernels);
  ShadowTestPass test(runtime, kernels);
  std::mt19937 rng(11);
  constexpr uint32_t kMap = 8;
  const cl::Buffer map = runtime.upload(std::vector<float>(kMap * kMap, 0.5f));
  const std::vector<LightMap> maps = {{ViewSetup{}, &map}};
  ShadowMapSettings settings;
  settings.size = kMap;
  for (auto [w, h] : {std::pair{8u, 8u}, {7u, 5u}, {333u, 77u}, {640u, 360u}}) {
    const RandomView v(runtime, w, h, rng);
    const Camera& cam = v.cam;
    const GBuffer& g = v.g;
    const uint32_t pixels = w * h;
    Timeline t;
    const std::optional<DepthRange> want = pass.run(g, cam, t);
    std::vector<float> plain(pixels), fused(pixels);
    runtime.read(test.run(g, pixels, maps, Light{}, settings, t), plain.data(), pixels * 4);
    const uint32_t strips = (pixels + kPcfStrip - 1) / kPcfStrip;
    const ViewDepthOut out = pass.out(cam, strips);
    runtime.read(test.run(g, pixels, maps, Light{}, settings, t, &out), fused.data(), pixels * 4);
    const std::optional<DepthRange> got = pass.read(strips, t);
    ASSERT_TRUE(want.has_value() && got.has_value()) << w << "x" << h;
    EXPECT_EQ(got->min, want->min) << w << "x" << h;
    EXPECT_EQ(got->max, want->max) << w << "x" << h;
    EXPECT_EQ(std::memcmp(plain.data(), fused.data(), pixels * 4), 0) << w << "x" << h;
  }
}

TEST(DepthRange, NoReceivingPixelGivesNothing) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  DepthRangePass pass(runtime, kernels);
  Camera cam;
  cam.width = 100, cam.height = 50;
  std::vector<float> pos(size_t{5000} * 3, 1.0f), nrm(size_t{5000} * 4, 0.0f);
  GBuffer g;
  g.position = runtime.upload(pos);
  g.normal = runtime.upload(nrm);
  runtime.finish();
  Timeline t;
  EXPECT_FALSE(pass.run(g, cam, t).has_value());
}

// A wall 10 m ahead seen from above, plus a small triangle of the same mesh far below the view
// near the camera: the mesh's box reaches almost to the eye, the visible pixels do not.
TEST(DepthRange, PsmNearIsTheNearestReceivingPixel) {
  auto scene = std::make_shared<Scene>();
  Mesh m;
  m.positions = {-30, -30, 0, 30, -30, 0, 30, 30,  0, -30, 30, 0,  // the wall, z = 0
                 -1,  -40, 9, 1,  -40, 9, 0,  -40, 8};             // below the view, near the eye
  m.indices = {0, 1, 2, 0, 2, 3, 4, 5, 6};
  scene->meshes = {m, testing::quad(1, 0)};
  scene->instances = {Instance{0}, Instance{1}};
  scene->instances[1].transform = glm::mat4(glm::vec4(1, 0, 0, 0), glm::vec4(0, 0, 1, 0),
                                            glm::vec4(0, -1, 0, 0), glm::vec4(0, 2, 3, 1));
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 4, 10};
  r.camera.target = {0, 0, 0};
  r.camera.width = 320, r.camera.height = 180;
  r.camera.near = 0.1f, r.camera.far = 100.0f;
  r.lights[0].direction = glm::normalize(glm::vec3(0.3f, -0.5f, -1.0f));
  r.shadow_map.size = 512;
  r.shadow_map.technique = Technique::kPsm;
  r.products = {Product::kShadowMap, Product::kPosition, Product::kVisibility};
  Engine& e = testing::engine();
  const RenderResult res = e.render(r);
  const Texture& pos = res.textures.at(1);
  std::vector<float> nrm(size_t{pos.width} * pos.height * 4, 1.0f);  // every instance receives
  const Reference want = reduce(pos.data, nrm, r.camera);
  const double vn = res.light_fits[0].virtual_near;
  std::printf(
      "[ depth    ] nearest receiving pixel %.6f, farthest %.6f; virtual near %.6f, far "
      "%.6f (%s)\n",
      want.min, want.max, vn, res.light_fits[0].virtual_far, res.light_fits[0].light_case.c_str());
  // The fit widens the measured range by 1e-3 of each end (+ 1e-6 of |eye| + far).
  const double coords = 1e-6 * (glm::length(glm::dvec3(r.camera.eye)) + want.max);
  EXPECT_LE(vn, want.min);
  EXPECT_GE(vn, want.min * (1 - 1e-3) - coords - 1e-5);
  EXPECT_GE(res.light_fits[0].virtual_far, want.max);
  EXPECT_LE(res.light_fits[0].virtual_far, want.max * (1 + 1e-3) + coords + 1e-5);
  // The bounding boxes alone would put it much nearer.
  const double box_near = fit_psm_light(r.lights[0], r.camera,
                                        {{Bounds{{-30, -40, 0}, {30, 30, 9}}, true, true},
                                         {Bounds{{-1, 1, 3}, {1, 3, 3}}, true, true}},
                                        PsmSettings{})
                              .virtual_near;
  std::printf("[ depth    ] bounding boxes alone: virtual near %.6f\n", box_near);
  EXPECT_LT(box_near, 0.5 * want.min);
}

}  // namespace
}  // namespace shadow
