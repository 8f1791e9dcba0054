// The receivers' depth range (the G-buffer resolve's partials, kernels/gbuffer.cl) against a
// double-precision reduction over the same G-buffer, and the engine feeding it to the PSM fit: with
// psm_near = RECEIVERS the virtual near plane sits at the nearest receiving pixel, not at the
// bounding boxes' nearest point.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "engine/engine.hpp"
#include "engine/passes/depth_range.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/scene_buffers.hpp"
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

// The G-buffer of `scene` seen by `cam`, resolved, and its depth range as the pass combines the
// resolve's partials; `pos` and `nrm` get the G-buffer's positions and normals.
std::optional<DepthRange> resolve(const Scene& scene, const Camera& cam, std::vector<float>& pos,
                                  std::vector<float>& nrm, double* device_ms = nullptr) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  Rasterizer rasterizer(runtime, kernels);
  GBufferPass gbuffer(runtime, kernels, rasterizer);
  DepthRangePass pass(runtime);
  Timeline t;
  const SceneBuffers buffers(runtime, kernels, scene, t);
  const GBuffer& g = gbuffer.run(scene, buffers, cam, camera_setup(cam), t);
  const size_t pixels = size_t{cam.width} * cam.height;
  pos.resize(pixels * 3), nrm.resize(pixels * 4);
  runtime.read(g.position, pos.data(), pos.size() * sizeof(float));
  runtime.read(g.normal, nrm.data(), nrm.size() * sizeof(float));
  Timeline range;
  const std::optional<DepthRange> got = pass.run(g, range);
  if (device_ms) *device_ms = range.timings().at(0).device_ms;
  return got;
}

// Random triangles around an eye far from the origin (as on the street), a third of them on
// instances that receive no shadows.
Scene far_triangles(const Camera& cam, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const glm::vec3 eye = cam.eye, fwd = glm::normalize(cam.target - cam.eye);
  Scene s;
  for (int m = 0; m < 3; ++m) {
    Mesh mesh;
    for (int t = 0; t < 300; ++t) {
      const glm::vec3 c = eye + fwd * (2.0f + 200.0f * (0.5f + 0.5f * u(rng))) +
                          glm::vec3(u(rng), u(rng), u(rng)) * 60.0f;
      for (int k = 0; k < 3; ++k) {
        const glm::vec3 p = c + glm::vec3(u(rng), u(rng), u(rng)) * 8.0f;
        mesh.positions.insert(mesh.positions.end(), {p.x, p.y, p.z});
        mesh.indices.push_back(uint32_t(mesh.indices.size()));
      }
    }
    s.meshes.push_back(mesh);
    Instance inst{uint32_t(m)};
    inst.receives_shadows = m != 0;
    s.instances.push_back(inst);
  }
  return s;
}

TEST(DepthRange, ResolvePartialsMatchTheDoubleReduction) {
  std::mt19937 rng(7);
  double worst = 0;
  // Sizes around the resolve's chunk (64 pixels): a ragged last chunk, 1080p.
  for (auto [w, h] : {std::pair{8u, 8u}, {333u, 77u}, {1920u, 1080u}}) {
    Camera cam;
    cam.eye = {1200.5f, 1.7f, -830.25f};
    cam.target = {1150.0f, 0.0f, -900.0f};
    cam.width = w, cam.height = h;
    cam.near = 0.1f, cam.far = 2000.0f;
    const Scene scene = far_triangles(cam, rng);
    std::vector<float> pos, nrm;
    double ms = 0;
    const std::optional<DepthRange> got = resolve(scene, cam, pos, nrm, &ms);
    const Reference want = reduce(pos, nrm, cam);
    ASSERT_TRUE(got.has_value()) << w << "x" << h;
    ASSERT_LT(want.min, want.max);
    const double scale = glm::length(glm::dvec3(cam.eye)) + want.max;
    const double err = std::max(std::abs(got->min - want.min), std::abs(got->max - want.max));
    worst = std::max(worst, err / scale);
    std::printf("[ depth    ] %ux%u: min %.9g (ref %.9g), max %.9g (ref %.9g), %.3f ms device\n", w,
                h, got->min, want.min, got->max, want.max, ms);
  }
  std::printf("[ depth    ] worst error / (|eye| + max depth) %.3g\n", worst);
  EXPECT_LT(worst, 1e-8);  // measured 5.0e-9: float dot product of float positions
}

TEST(DepthRange, NoReceivingPixelGivesNothing) {
  std::mt19937 rng(3);
  Camera cam;
  cam.eye = {0, 2, 10};
  cam.target = {0, 0, 0};
  cam.width = 100, cam.height = 50;
  Scene scene = far_triangles(cam, rng);
  for (Instance& i : scene.instances) i.receives_shadows = false;
  std::vector<float> pos, nrm;
  EXPECT_FALSE(resolve(scene, cam, pos, nrm).has_value());
  bool seen = false;  // the triangles are in view
  for (size_t p = 0; p < pos.size() / 3; ++p) seen |= !std::isnan(pos[3 * p]);
  EXPECT_TRUE(seen);
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
  Engine& e = testing::shared_engine();
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
