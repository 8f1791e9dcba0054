// Ping-pong blur (Kozlov 14.4.2): the separable Gaussian against a double-precision CPU blur
// with the same float weights and edge rule; one-hot class planes against the ids resolved on
// the CPU; end to end, a class-0 ground under an occluder against the CPU blur of the hard
// footprint read back from the shadow map, while receivers without a class keep the hard test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "engine/engine.hpp"
#include "engine/passes/blur.hpp"
#include "engine_fixture.hpp"

namespace shadow {
namespace {

struct Device {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  BlurPass blur{runtime, kernels};
};
Device& device() {
  static Device d;
  return d;
}
using testing::engine;

// planes x h x w, in place, `passes` x (rows then columns), edges clamped, taps -r..r in order.
void cpu_blur(std::vector<double>& v, uint32_t w, uint32_t h, uint32_t planes, uint32_t radius,
              uint32_t passes) {
  const std::vector<float> wt = BlurPass::weights(radius);
  const int r = int(radius);
  std::vector<double> t(v.size());
  for (uint32_t pass = 0; pass < passes; ++pass) {
    for (uint32_t k = 0; k < planes; ++k)
      for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
          double a = 0;
          for (int d = -r; d <= r; ++d)
            a += double(wt[d + r]) *
                 v[(size_t(k) * h + y) * w + std::clamp(int(x) + d, 0, int(w) - 1)];
          t[(size_t(k) * h + y) * w + x] = a;
        }
    for (uint32_t k = 0; k < planes; ++k)
      for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
          double a = 0;
          for (int d = -r; d <= r; ++d)
            a += double(wt[d + r]) *
                 t[(size_t(k) * h + std::clamp(int(y) + d, 0, int(h) - 1)) * w + x];
          v[(size_t(k) * h + y) * w + x] = a;
        }
  }
}

TEST(Blur, WeightsAreANormalizedGaussian) {
  const std::vector<float> w = BlurPass::weights(4);  // sigma 2
  ASSERT_EQ(w.size(), 9u);
  double sum = 0;
  for (float x : w) sum += x;
  EXPECT_NEAR(sum, 1.0, 1e-6);
  EXPECT_NEAR(w[4 + 2] / w[4], std::exp(-0.5), 1e-6);  // one sigma out
}

TEST(Blur, SeparableGaussianMatchesCpu) {
  Device& d = device();
  struct Case {
    uint32_t w, h, planes, radius, passes;
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (const Case c : {Case{1, 1, 1, 3, 1}, Case{37, 23, 2, 5, 3}, Case{130, 70, 4, 32, 2},
                       Case{300, 5, 1, 1, 16}}) {
    std::vector<float> in(size_t{c.w} * c.h * c.planes);
    for (float& x : in) x = u(rng);
    cl::Buffer buf = d.runtime.upload(in);
    Timeline tl;
    d.blur.blur(buf, c.w, c.h, c.planes, c.radius, c.passes, tl);
    std::vector<float> out(in.size());
    d.runtime.read(buf, out.data(), out.size() * sizeof(float));
    d.runtime.finish();
    std::vector<double> ref(in.begin(), in.end());
    cpu_blur(ref, c.w, c.h, c.planes, c.radius, c.passes);
    double err = 0;
    for (size_t i = 0; i < out.size(); ++i) err = std::max(err, std::abs(out[i] - ref[i]));
    std::printf("blur %ux%u x%u r=%u passes=%u: max |gpu - cpu| = %.3g\n", c.w, c.h, c.planes,
                c.radius, c.passes, err);
    EXPECT_LT(err, 1e-6);
  }
}

TEST(Blur, ClassPlanesFromIds) {
  Device& d = device();
  // Draws with first primitives 0, 10, 25, 40, 41 and classes none, 0, 3, 1, 2.
  const uint32_t first[] = {0, 10, 25, 40, 41};
  const int cls[] = {-1, 0, 3, 1, 2};
  std::vector<DrawItem> draws(5);
  for (int i = 0; i < 5; ++i) {
    draws[i].out_triangle_base = first[i];
    draws[i].flags = kDrawReceives | uint32_t(cls[i] + 1) << kDrawClassShift;
  }
  const uint32_t size = 67, planes = 4;
  std::mt19937 rng(3);
  std::vector<uint32_t> ids(size * size);
  for (uint32_t& id : ids) id = rng() % 8 == 0 ? 0xffffffffu : rng() % 50;
  RasterOutput raster;
  raster.ids = d.runtime.upload(ids);
  raster.draws = d.runtime.upload(draws);
  Timeline tl;
  const cl::Buffer& out = d.blur.classify(raster, 5, size, planes, tl);
  std::vector<float> got(size_t{size} * size * planes);
  d.runtime.read(out, got.data(), got.size() * sizeof(float));
  d.runtime.finish();
  size_t wrong = 0, ones = 0;
  for (uint32_t t = 0; t < size * size; ++t) {
    int c = -1;
    if (ids[t] != 0xffffffffu)
      for (int i = 0; i < 5; ++i)
        if (ids[t] >= first[i]) c = cls[i];
    for (uint32_t k = 0; k < planes; ++k) {
      const float want = c == int(k) ? 1.0f : 0.0f;
      wrong += got[size_t{k} * size * size + t] != want;
      ones += want == 1.0f;
    }
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(ones, size * size / 2);
}

// Ground 16 x 16 at y = 0; occluder 2 x 2 at y = 1 (no class); a small plain receiver at
// y = 0.5 half under the occluder; sun straight down.
RenderRequest ground_scene(uint32_t ground_class, FilterKind filter) {
  auto scene = std::make_shared<Scene>();
  const auto quad = [](float x0, float x1, float y, float z0, float z1) {
    return Mesh{{x0, y, z0, x1, y, z0, x1, y, z1, x0, y, z1}, {0, 2, 1, 0, 3, 2}, {}, {}};
  };
  scene->meshes = {quad(-8, 8, 0, -8, 8), quad(-1, 1, 1, -1, 1),
                   quad(0.5f, 2.5f, 0.5f, -0.5f, 0.5f)};
  Instance ground{0};
  ground.receiver_class = ground_class;
  scene->instances = {ground, Instance{1}, Instance{2}};
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 7, 6};
  r.camera.target = {0, 0, 0};
  r.camera.width = 320;
  r.camera.height = 240;
  r.camera.near = 0.1f;
  r.camera.far = 50.0f;
  r.lights[0].direction = {0, -1, 0};
  r.shadow_map.size = 512;
  r.filter.kind = filter;
  r.filter.blur = {8, 2};
  r.products = {Product::kVisibility, Product::kPosition, Product::kShadowMap};
  return r;
}

TEST(Blur, GroundGetsTheBlurredFootprintOthersTheHardTest) {
  const RenderResult blurred = engine().render(ground_scene(0, FilterKind::kBlur));
  const RenderResult hard = engine().render(ground_scene(Instance::kNoClass, FilterKind::kHard));
  const RenderResult unclassed =
      engine().render(ground_scene(Instance::kNoClass, FilterKind::kBlur));
  const Texture &vis = blurred.textures[0], &pos = blurred.textures[1], &map = blurred.textures[2];
  const Texture& hard_vis = hard.textures[0];
  // No class: exactly the hard test (bitwise, NaN included); the ground casts anyway: same map.
  const auto same = [](const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
  };
  EXPECT_TRUE(same(unclassed.textures[0].data, hard_vis.data));
  EXPECT_TRUE(same(map.data, hard.textures[2].data));

  // The ground's one-hot plane from the map's depths: the occluder is near z = 0, the small
  // receiver near 0.5, the ground just below 1 and empty texels (past the ground) exactly 1.
  const uint32_t n = map.width;
  std::vector<double> plane(size_t{n} * n);
  for (size_t t = 0; t < plane.size(); ++t) plane[t] = map.data[t] > 0.75f && map.data[t] < 1.0f;
  cpu_blur(plane, n, n, 1, 8, 2);
  const glm::dmat4 m(map.world_to_ndc);
  const auto sample = [&](glm::dvec3 x) {
    const glm::dvec4 c = m * glm::dvec4(x, 1.0);
    const double fx = c.x / c.w * n - 0.5, fy = c.y / c.w * n - 0.5;
    const double ix = std::floor(fx), iy = std::floor(fy), ax = fx - ix, ay = fy - iy;
    const auto at = [&](double i, double j) {
      return plane[size_t(std::clamp(int(j), 0, int(n) - 1)) * n +
                   std::clamp(int(i), 0, int(n) - 1)];
    };
    return (1 - ay) * ((1 - ax) * at(ix, iy) + ax * at(ix + 1, iy)) +
           ay * ((1 - ax) * at(ix, iy + 1) + ax * at(ix + 1, iy + 1));
  };
  double err = 0;
  size_t ground = 0, penumbra = 0, other = 0, other_diff = 0, hard_penumbra = 0;
  for (size_t p = 0; p < vis.data.size(); ++p) {
    const glm::dvec3 x(pos.data[3 * p], pos.data[3 * p + 1], pos.data[3 * p + 2]);
    if (std::isnan(x.x)) continue;
    if (std::abs(x.y) < 1e-3) {
      ++ground;
      const double e = std::abs(vis.data[p] - sample(x));
      err = std::max(err, e);
      penumbra += vis.data[p] > 0.05f && vis.data[p] < 0.95f;
      hard_penumbra += hard_vis.data[p] > 0.05f && hard_vis.data[p] < 0.95f;
    } else {
      ++other;
      other_diff += vis.data[p] != hard_vis.data[p];
    }
  }
  std::printf(
      "blur ground: %zu pixels, max |engine - cpu blur of footprint| = %.3g, %zu in the "
      "penumbra (hard: %zu); other receivers: %zu pixels, %zu differ from hard\n",
      ground, err, penumbra, hard_penumbra, other, other_diff);
  EXPECT_GT(ground, 20000u);
  EXPECT_GT(other, 1000u);
  EXPECT_LT(err, 1e-5);
  EXPECT_GT(penumbra, 1000u);
  EXPECT_EQ(hard_penumbra, 0u);
  EXPECT_EQ(other_diff, 0u);
}

}  // namespace
}  // namespace shadow
