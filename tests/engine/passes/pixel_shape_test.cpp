// The GPU shape of the per-pixel passes (issue 42, engine/passes/pixel_shape.hpp): the hard test,
// PCF 2x2, Poisson PCF, PCSS, texel density and the G-buffer resolve, a work-item per pixel in
// work-groups of the profile's size, on PoCL. Each is the CPU shape's kernel built with a strip
// of one pixel, so on one device both give the same bits: checked with memcmp, pass by pass on
// receivers that reach every case (the sky, non-receivers, sides facing away, off the map,
// outside a spot's cone, tilted planes), at pixel counts that are not multiples of the group
// size, and through whole renders under EngineOptions::kernel_profile "cpu" and "gpu". The GPU
// shape also meets the references pcf_test.cpp and pcss_test.cpp hold the CPU shape to.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <optional>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/engine.hpp"
#include "engine/passes/depth_range.hpp"
#include "engine/passes/edge_sampling.hpp"
#include "engine/passes/pcf.hpp"
#include "engine/passes/pcss.hpp"
#include "engine/passes/poisson_disk.hpp"
#include "engine/passes/shadow_test.hpp"
#include "engine_fixture.hpp"
#include "occluder_scene.hpp"
#include "sun_edge_scene.hpp"

namespace shadow {
namespace {

// One device per shape, with the passes under test.
struct Shape : testing::ProfileDevice {
  using ProfileDevice::ProfileDevice;
  ShadowTestPass hard{runtime, kernels};
  PcfPass pcf{runtime, kernels};
  EdgeSamplingPass edge{runtime, kernels};
  PcssPass pcss{runtime, kernels};
  DepthRangePass depth{runtime, kernels};
  GBuffer g;
  cl::Buffer map;

  void upload(const std::vector<float>& pos, const std::vector<float>& nrm,
              const std::vector<float>& depth) {
    g.position = runtime.upload(pos);
    g.normal = runtime.upload(nrm);
    map = runtime.upload(depth);
    runtime.finish();  // the uploads read these vectors asynchronously
  }
};

Shape& cpu() {
  static Shape s("cpu");
  return s;
}
Shape& gpu() {
  static Shape s("gpu");
  return s;
}

// memcmp, and where it fails the first pixel that differs.
void expect_same_bits(const std::vector<float>& a, const std::vector<float>& b,
                      const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  if (std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0) return;
  size_t first = 0, count = 0;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0) first = count++ ? first : i;
  ADD_FAILURE() << what << ": " << count << " of " << a.size() << " pixels differ, the first "
                << first << " (cpu " << a[first] << ", gpu " << b[first] << ")";
}

constexpr uint32_t kPixels = 4001;  // neither a multiple of a strip (64) nor of a group
// Besides the whole image: under a strip, under a group, a group and one.
constexpr uint32_t kPartCounts[] = {1, 63, 255, 257};

TEST(PixelShape, TheProfilesPickTheirShapes) {
  const cl::DeviceProfile& p = gpu().runtime.device_info().profile();
  ASSERT_EQ(p.shape, cl::KernelShape::kGpu);
  EXPECT_GT(p.group_size, 1u);
  const PixelShape g = pcf_shape(gpu().runtime), c = pcf_shape(cpu().runtime);
  std::printf("GPU shape on %s: work-groups of %zu\n", gpu().runtime.device_name().c_str(),
              g.group);
  EXPECT_EQ(g.group, p.group_size);
  EXPECT_EQ(g.work_items(kPixels), kPixels);
  EXPECT_EQ(g.with("-DCUBE_FACES"),
            "-DCUBE_FACES -DPIXEL_CHUNK=1 -DGROUP_SIZE=" + std::to_string(p.group_size));
  // The CPU shape keeps the kernels' own options, so its programs are the ones it always built.
  EXPECT_EQ(c.group, 1u);
  EXPECT_EQ(c.work_items(kPixels), (kPixels + 63) / 64);
  EXPECT_EQ(c.with("-DCUBE_FACES"), "-DCUBE_FACES");
  EXPECT_EQ(c.with(""), "");
  // The options reach the program: its kernel requires the profile's work-group size.
  for (Shape* sh : {&cpu(), &gpu()}) {
    size_t required[3] = {};
    cl_kernel k = sh->kernels.kernel("pcf.cl", "pcf", pcf_shape(sh->runtime).with(""));
    ASSERT_EQ(clGetKernelWorkGroupInfo(k, sh->runtime.device(), CL_KERNEL_COMPILE_WORK_GROUP_SIZE,
                                       sizeof required, required, nullptr),
              CL_SUCCESS);
    EXPECT_EQ(required[0], pcf_shape(sh->runtime).group);
  }
}

// Receivers in the map's own space (ViewSetup{}: world = texture NDC) against a 64^2 map of
// random depths, with every case of the set-up.
void upload_receivers(uint32_t map_size) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> pos, nrm, depth(size_t{map_size} * map_size);
  for (float& z : depth) z = u(rng) < 0.1f ? 1.0f : 0.3f + 0.7f * u(rng);
  for (uint32_t p = 0; p < kPixels; ++p) {
    const float x = -0.1f + 1.2f * u(rng), y = -0.1f + 1.2f * u(rng);  // some off the map
    const float kind = u(rng);
    glm::vec4 n(-0.3f + 0.6f * u(rng), -0.3f + 0.6f * u(rng), 1.0f, 1.0f);
    if (kind < 0.03f)
      n = {0, 0, 1, 0};  // not a receiver
    else if (kind < 0.06f)
      n = {0, 0, -1, 1};  // faces away from the light
    else if (kind < 0.12f)
      n = {1, 0.2f, 0.1f, 1};  // about the x axis: the other tangent
    const glm::vec3 nn = glm::normalize(glm::vec3(n));
    if (kind >= 0.94f && kind < 0.97f)
      pos.insert(pos.end(), {NAN, NAN, NAN});  // the sky
    else
      pos.insert(pos.end(), {x, y, 0.35f + 0.3f * x + 0.2f * y + 0.05f * u(rng)});
    nrm.insert(nrm.end(), {nn.x, nn.y, nn.z, n.w});
  }
  cpu().upload(pos, nrm, depth);
  gpu().upload(pos, nrm, depth);
}

std::vector<Light> test_lights() {
  Light sun;
  sun.direction = {0.1f, 0.0f, -1.0f};
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0.5f, 0.5f, -1.0f};
  spot.direction = {0, 0, 1};
  spot.cone_angle_deg = 50.0f;  // part of the image outside
  return {sun, spot};
}

TEST(PixelShape, HardTestPcfAndEdgeAreTheCpuShapesBits) {
  constexpr uint32_t kMap = 64;
  upload_receivers(kMap);
  ShadowMapSettings s;
  s.size = kMap;
  s.bias_constant = 1e-3f;
  s.bias_slope = 0.75f;
  const std::vector<PcfParams> filters = {
      {PcfParams::Mode::kBilinear},
      {PcfParams::Mode::kPoisson, 1, 2.0f, true},
      {PcfParams::Mode::kPoisson, 16, 2.0f, true},
      {PcfParams::Mode::kPoisson, 17, 3.0f, false},  // odd: the last tap alone
      {PcfParams::Mode::kPoisson, 64, 4.0f, true}};
  int light_index = 0;
  for (const Light& light : test_lights()) {
    const std::string l = "light " + std::to_string(light_index++);
    // `width` seeds Poisson's rotation: rows shorter than a strip, and longer.
    for (uint32_t width : {61u, kPixels}) {
      std::map<std::string, std::vector<float>> whole;  // the GPU shape's, over every pixel
      for (uint32_t pixels : {kPixels, 1u, 63u, 255u, 257u}) {
        const std::string at =
            l + ", width " + std::to_string(width) + ", " + std::to_string(pixels) + " pixels";
        auto both = [&](const std::string& what, auto run) {
          const std::vector<float> a = run(cpu()), b = run(gpu());
          expect_same_bits(a, b, what + ", " + at);
          if (pixels == kPixels)
            whole[what] = b;
          else  // a smaller launch gives its pixels what the whole image gave them
            expect_same_bits(std::vector<float>(whole[what].begin(), whole[what].begin() + pixels),
                             b, what + " (part of the whole), " + at);
        };
        Timeline t;
        both("hard", [&](Shape& sh) {
          const std::vector<LightMap> maps = {{ViewSetup{}, &sh.map}};
          return sh.read(sh.hard.run(sh.g, pixels, maps, light, s, t), pixels);
        });
        for (const PcfParams& f : filters)
          both("pcf mode " + std::to_string(int(f.mode)) + " taps " + std::to_string(f.taps),
               [&](Shape& sh) {
                 const std::vector<LightMap> maps = {{ViewSetup{}, &sh.map}};
                 return sh.read(sh.pcf.run(sh.g, pixels, width, maps, light, s, f, t), pixels);
               });
        double means[2];
        both("edge", [&](Shape& sh) {
          const std::vector<LightMap> maps = {{ViewSetup{}, &sh.map}};
          means[&sh == &gpu()] = sh.edge.run(sh.g, pixels, 1, maps, light, s, t);
          return sh.read(sh.edge.difference(), pixels);
        });
        EXPECT_EQ(means[0], means[1]) << at;
      }
      // Every case was reached: lit, shadowed, in between, the sky.
      const std::vector<float>& v = whole["pcf mode 1 taps 16"];
      size_t lit = 0, dark = 0, soft = 0, sky = 0;
      for (float x : v) {
        if (std::isnan(x))
          ++sky;
        else if (x == 1)
          ++lit;
        else if (x == 0)
          ++dark;
        else
          ++soft;
      }
      EXPECT_GT(lit, 100u) << l;
      EXPECT_GT(dark, 100u) << l;
      EXPECT_GT(soft, 100u) << l;
      EXPECT_GT(sky, 10u) << l;
    }
  }
}

// A quality probe's hard test writes the view-depth range's partials, one per strip of 64 pixels,
// on both profiles (the GPU profile keeps the strips there): the same range, the same test.
TEST(PixelShape, TheProbesViewDepthIsTheSame) {
  upload_receivers(64);
  ShadowMapSettings s;
  s.size = 64;
  Camera camera;
  camera.eye = {0.5f, 0.5f, -2.0f};
  camera.target = {0.5f, 0.5f, 0.5f};
  const uint32_t strips = (kPixels + kPcfStrip - 1) / kPcfStrip;
  std::optional<DepthRange> range[2];
  std::vector<float> vis[2];
  for (Shape* sh : {&cpu(), &gpu()}) {
    Timeline t;
    const ViewDepthOut out = sh->depth.out(camera, strips);
    const std::vector<LightMap> maps = {{ViewSetup{}, &sh->map}};
    vis[sh == &gpu()] = sh->read(sh->hard.run(sh->g, kPixels, maps, Light{}, s, t, &out), kPixels);
    range[sh == &gpu()] = sh->depth.read(strips, t);
  }
  ASSERT_TRUE(range[0] && range[1]);
  EXPECT_EQ(range[0]->min, range[1]->min);
  EXPECT_EQ(range[0]->max, range[1]->max);
  expect_same_bits(vis[0], vis[1], "hard test with the view depth");
}

// The view-depth range on its own (DepthRangePass::run: depth_range.cl's work-item per 4096 pixels,
// or its work-group per 4096): over three chunks and a part, with sky pixels,
// non-receivers and the extremes in different chunks, the same range in both shapes, and a
// double-precision reference's within float rounding.
TEST(PixelShape, TheViewDepthRangeIsTheSame) {
  constexpr uint32_t kCount = 3 * DepthRangePass::kChunk + 77;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  std::vector<float> pos, nrm;
  Camera camera;
  camera.eye = {0.5f, 0.5f, -2.0f};
  camera.target = {0.5f, 0.5f, 0.5f};
  camera.width = kCount;
  camera.height = 1;
  double lo = INFINITY, hi = -INFINITY;
  for (uint32_t p = 0; p < kCount; ++p) {
    const bool sky = p % 97 == 5, receives = p % 13 != 0;
    const glm::vec3 x(u(rng), u(rng), p == 9000 ? 40.0f : p == 100 ? -1.5f : u(rng) + 6.0f);
    if (sky)
      pos.insert(pos.end(), {NAN, NAN, NAN});
    else
      pos.insert(pos.end(), {x.x, x.y, x.z});
    nrm.insert(nrm.end(), {0.0f, 0.0f, -1.0f, receives ? 1.0f : 0.0f});
    if (!sky && receives) {
      const double d = double(x.z) + 2.0;  // forward is +z from the eye at z = -2
      lo = std::min(lo, d), hi = std::max(hi, d);
    }
  }
  std::optional<DepthRange> range[2];
  for (Shape* sh : {&cpu(), &gpu()}) {
    sh->upload(pos, nrm, std::vector<float>(1, 1.0f));
    Timeline t;
    range[sh == &gpu()] = sh->depth.run(sh->g, camera, t);
  }
  ASSERT_TRUE(range[0] && range[1]);
  EXPECT_EQ(range[0]->min, range[1]->min);
  EXPECT_EQ(range[0]->max, range[1]->max);
  EXPECT_NEAR(range[0]->min, lo, 1e-5);  // the extremes, in chunks 0 and 2
  EXPECT_NEAR(range[0]->max, hi, 1e-5);
  EXPECT_NEAR(hi, 42.0, 1e-9);
  EXPECT_NEAR(lo, 0.5, 1e-9);
}

// PCSS with a light view of its own: a sun (orthographic) and a spot (perspective) over a ground
// at y = 0 with random blockers in the map above it.
TEST(PixelShape, PcssIsTheCpuShapesBits) {
  constexpr uint32_t kMap = 64;
  const glm::dmat4 to_texture = glm::translate(glm::dmat4(1.0), glm::dvec3(0.5)) *
                                glm::scale(glm::dmat4(1.0), glm::dvec3(0.5));
  const glm::dmat4 view =
      glm::lookAt(glm::dvec3(0, 5, 0), glm::dvec3(0, 0, 0), glm::dvec3(0, 0, -1));
  Light sun;
  sun.direction = {0, -1, 0};
  sun.size = 20.0f;  // degrees
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0, 5, 0};
  spot.direction = {0, -1, 0};
  spot.cone_angle_deg = 100.0f;
  spot.size = 1.0f;
  struct Case {
    Light light;
    ViewSetup setup;
  };
  std::vector<Case> cases(2);
  cases[0].light = sun;
  cases[0].setup.view = view;
  cases[0].setup.world_to_ndc = to_texture * glm::ortho(-10.0, 10.0, -10.0, 10.0, 0.1, 20.0) * view;
  cases[1].light = spot;
  cases[1].setup.view = view;
  cases[1].setup.world_to_ndc =
      to_texture * glm::perspective(glm::radians(100.0), 1.0, 0.5, 20.0) * view;
  for (const Case& c : cases) {
    // The ground's depth in this map, and blockers a little nearer than it.
    const glm::dvec4 centre = c.setup.world_to_ndc * glm::dvec4(0, 0, 0, 1);
    const float ground = float(centre.z / centre.w);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> pos, nrm, depth(kMap * kMap);
    for (float& z : depth) z = u(rng) < 0.4f ? 1.0f : ground * (0.85f + 0.2f * u(rng));
    for (uint32_t p = 0; p < kPixels; ++p) {
      const float x = -12 + 24 * u(rng), z = -12 + 24 * u(rng), kind = u(rng);
      pos.insert(pos.end(), {kind < 0.03f ? NAN : x, 0.0f, z});
      const float w = kind >= 0.03f && kind < 0.06f ? 0.0f : 1.0f;  // not a receiver
      if (kind >= 0.06f && kind < 0.09f)
        nrm.insert(nrm.end(), {0, -1, 0, 1});  // faces away: dark
      else if (kind >= 0.09f && kind < 0.2f)
        nrm.insert(nrm.end(), {0.6f, 0.8f, 0, w});  // tilted
      else
        nrm.insert(nrm.end(), {0, 1, 0, w});
    }
    cpu().upload(pos, nrm, depth);
    gpu().upload(pos, nrm, depth);
    ShadowMapSettings s;
    s.size = kMap;
    const std::string l = c.light.type == LightType::kSpot ? "spot" : "sun";
    for (const PcssSettings& params : {PcssSettings{16, 32, true}, PcssSettings{7, 9, false}}) {
      std::vector<float> whole;
      for (uint32_t pixels : {kPixels, 1u, 63u, 255u, 257u}) {
        const std::string at = l + " " + std::to_string(params.blocker_samples) + "/" +
                               std::to_string(params.filter_samples) + ", " +
                               std::to_string(pixels) + " pixels";
        std::vector<float> out[2];
        for (Shape* sh : {&cpu(), &gpu()}) {
          Timeline t;
          out[sh == &gpu()] = sh->read(
              sh->pcss.run(sh->g, pixels, 61, sh->map, c.setup, c.light, s, params, t), pixels);
        }
        expect_same_bits(out[0], out[1], "pcss, " + at);
        if (pixels == kPixels) {
          whole = out[1];
          size_t soft = 0;
          for (float v : whole) soft += v > 0 && v < 1;
          EXPECT_GT(soft, 200u) << at;  // penumbrae were found and filtered
        } else {
          expect_same_bits(std::vector<float>(whole.begin(), whole.begin() + pixels), out[1],
                           "pcss (part of the whole), " + at);
        }
      }
    }
  }
}

// pcf_test.cpp's references, on the GPU shape: receivers on z = 0.5 across a straight edge.
TEST(PixelShape, GpuPcfMeetsTheEdgeReferences) {
  constexpr uint32_t kMap = 64;
  constexpr int kEdge = 30;
  std::vector<float> pos, nrm, depth(kMap * kMap), u;
  for (uint32_t j = 0; j < kMap; ++j)
    for (uint32_t i = 0; i < kMap; ++i) depth[j * kMap + i] = int(i) < kEdge ? 0.2f : 1.0f;
  const float span = 5.0f;
  for (uint32_t p = 0; p < kPixels; ++p) {
    const float x = kEdge - span + 2 * span * p / (kPixels - 1);
    u.push_back(x);
    pos.insert(pos.end(), {x / kMap, 20.3f / kMap, 0.5f});
    nrm.insert(nrm.end(), {0, 0, 1, 1});
  }
  Shape& sh = gpu();
  sh.upload(pos, nrm, depth);
  Light light;
  light.direction = {0, 0, -1};
  ShadowMapSettings s;
  s.size = kMap;
  s.bias_constant = 0;
  s.bias_slope = 0;
  auto run = [&](const PcfParams& params) {
    Timeline t;
    return sh.read(
        sh.pcf.run(sh.g, kPixels, kPixels, {{ViewSetup{}, &sh.map}}, light, s, params, t), kPixels);
  };
  // Bilinear 2x2: the one-texel linear ramp.
  const std::vector<float> bilinear = run({PcfParams::Mode::kBilinear});
  double err = 0;
  for (uint32_t p = 0; p < kPixels; ++p)
    err = std::max(err, std::abs(bilinear[p] - std::clamp(double(u[p]) - kEdge + 0.5, 0.0, 1.0)));
  EXPECT_LT(err, 1e-5);
  // Poisson, not rotated: the taps a CPU replay counts past the edge.
  for (uint32_t taps : {1u, 16u, 64u}) {
    const float radius = 4.0f;
    const std::vector<float> vis = run({PcfParams::Mode::kPoisson, taps, radius, false});
    const std::vector<glm::vec2> disk = poisson_disk(taps);
    int mismatches = 0;
    for (uint32_t p = 0; p < kPixels; ++p) {
      int lit = 0;
      for (const glm::vec2& t : disk) lit += std::floor(u[p] + radius * t.x) >= kEdge;
      if (std::abs(vis[p] - float(lit) / taps) > 1e-6f) ++mismatches;
    }
    EXPECT_LE(mismatches, 2) << taps;
  }
  // Rotated: the disk's area fraction past the edge, within 64 taps' sampling error.
  const std::vector<float> rotated = run({PcfParams::Mode::kPoisson, 64, 4.0f, true});
  err = 0;
  for (uint32_t p = 0; p < kPixels; ++p) {
    const double d = std::clamp((double(u[p]) - kEdge) / 4.0, -1.0, 1.0);
    err = std::max(err,
                   std::abs(rotated[p] - (1 - (std::acos(d) - d * std::sqrt(1 - d * d)) / M_PI)));
  }
  EXPECT_LT(err, 0.09);
}

void expect_same_textures(const RenderRequest& r, const std::string& what) {
  // Whole renders: one engine per profile (each compiles its own variants at start-up).
  const RenderResult a = testing::engine("cpu").render(r), b = testing::engine("gpu").render(r);
  EXPECT_EQ(a.passes, b.passes) << what;  // the same passes, only shaped differently
  ASSERT_EQ(a.textures.size(), b.textures.size()) << what;
  for (size_t i = 0; i < a.textures.size(); ++i) {
    const Texture &x = a.textures[i], &y = b.textures[i];
    ASSERT_EQ(x.name, y.name) << what;
    EXPECT_EQ(x.width, y.width) << what << " " << x.name;
    EXPECT_EQ(x.height, y.height) << what << " " << x.name;
    EXPECT_EQ(x.world_to_ndc, y.world_to_ndc) << what << " " << x.name;
    expect_same_bits(x.data, y.data, what + " " + x.name);
  }
  ASSERT_EQ(a.quality.has_value(), b.quality.has_value()) << what;
  if (a.quality) {
    EXPECT_EQ(a.quality->technique, b.quality->technique) << what;
    EXPECT_EQ(a.quality->size, b.quality->size) << what;
    EXPECT_EQ(a.quality->predicted_error, b.quality->predicted_error) << what;
  }
}

TEST(PixelShape, RendersUnderBothProfilesAreBitIdentical) {
  RenderRequest base = testing::occluder_request();
  base.camera.width = 203;  // 23 751 pixels: not a multiple of a strip or a group
  base.camera.height = 117;
  base.shadow_map.size = 300;
  base.lights[0].size = 8.0f;
  base.products = {Product::kVisibility, Product::kPosition, Product::kTexelDensity};
  std::vector<std::pair<std::string, Filter>> filters(6);
  filters[0].first = "hard";
  filters[1].first = "pcf 2x2", filters[1].second.kind = FilterKind::kPcf2x2;
  filters[2].first = "poisson 16", filters[2].second.kind = FilterKind::kPoisson;
  filters[3].first = "poisson 17", filters[3].second.kind = FilterKind::kPoisson;
  filters[3].second.poisson = {17, 3.0f, false};
  filters[4].first = "pcss 16/32", filters[4].second.kind = FilterKind::kPcss;
  filters[5].first = "pcss 7/9", filters[5].second.kind = FilterKind::kPcss;
  filters[5].second.pcss = {7, 9, false};

  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0.5f, 8.0f, 0.3f};
  spot.direction = {0, -1, 0};
  spot.cone_angle_deg = 100.0f;
  spot.size = 0.5f;
  Light point;
  point.type = LightType::kPoint;
  point.position = {0.3f, 4.0f, 0.2f};
  point.size = 0.2f;
  for (const auto& [name, filter] : filters) {
    RenderRequest r = base;
    r.filter = filter;
    expect_same_textures(r, "sun, " + name);
    r.lights = {spot};
    expect_same_textures(r, "spot, " + name);
    if (filter.kind != FilterKind::kPcss) {  // cube maps: each pixel in its face
      r.lights = {point};
      expect_same_textures(r, "point, " + name);
    }
  }
  // AUTO's trial (the edge mode), PSM, a quality goal (the probe's hard test), a tiny image.
  RenderRequest r = base;
  r.shadow_map.technique = Technique::kAuto;
  expect_same_textures(r, "auto");
  r.shadow_map.technique = Technique::kPsm;
  expect_same_textures(r, "psm");
  r.shadow_map.technique = Technique::kDefault;
  r.filter.kind = FilterKind::kPcf2x2;
  r.quality = {Quality::Goal::kMaxError, 1.0};
  expect_same_textures(r, "quality goal");
  r = base;
  r.camera.width = 7, r.camera.height = 5;
  for (FilterKind kind : {FilterKind::kPoisson, FilterKind::kPcss}) {
    r.filter.kind = kind;
    expect_same_textures(r, "7x5, filter " + std::to_string(int(kind)));
  }
}

// pcss_test.cpp's reference on the GPU profile: the ground's visibility across a straight edge
// under a sun of angular diameter theta follows the visible share of the sun's disk.
TEST(PixelShape, GpuPcssFollowsTheDiskSegment) {
  const float h = 1.0f, theta = 16.0f;
  const RenderRequest r = testing::sun_edge_request(h, theta, 240, 160);
  const RenderResult res = testing::engine("gpu").render(r);
  const Texture &vis = res.textures[0], &pos = res.textures[1];
  const double half = h * std::tan(0.5 * theta * M_PI / 180);
  double err = 0;
  size_t n = 0;
  for (size_t p = 0; p < size_t{vis.width} * vis.height; ++p) {
    const float x = pos.data[3 * p], y = pos.data[3 * p + 1], z = pos.data[3 * p + 2];
    if (std::isnan(x) || std::abs(y) > 1e-3f || std::abs(z) > 2.0f || std::abs(x) > 1.5 * half)
      continue;
    const double s = x / half;
    err += std::abs(vis.data[p] - testing::disk_fraction(s));
    ++n;
  }
  ASSERT_GT(n, 1000u);
  std::printf("GPU-shaped PCSS: %zu pixels, MAE vs disk segment %.4f\n", n, err / n);
  EXPECT_LT(err / n, 0.025);  // pcss_test.cpp's bound (measured 0.013 there)
}

}  // namespace
}  // namespace shadow
