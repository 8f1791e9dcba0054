// PCF on a straight shadow edge: bilinear 2x2 gives the one-texel linear ramp exactly; Poisson
// PCF gives the tap count a CPU replay predicts and, rotated, the disk's area fraction past the
// edge within the sampling error of N taps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "engine/passes/edge_sampling.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/pcf.hpp"
#include "engine/passes/poisson_disk.hpp"
#include "engine/passes/shadow_test.hpp"

namespace shadow {
namespace {

constexpr uint32_t kMap = 64;  // texels
constexpr int kEdge = 30;      // texels i < kEdge hold an occluder at depth 0.2
constexpr uint32_t kPixels = 4001;

struct Fixture {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  PcfPass pcf{runtime, kernels};
  GBuffer g;
  cl::Buffer map;
  std::vector<float> u;  // each pixel's map coordinate in texels

  // Receivers on the plane z = 0.5 (NDC = world: identity matrix), across the edge at row 20.
  Fixture(float span) {
    std::vector<float> pos, nrm, depth(kMap * kMap);
    for (uint32_t j = 0; j < kMap; ++j)
      for (uint32_t i = 0; i < kMap; ++i) depth[j * kMap + i] = int(i) < kEdge ? 0.2f : 1.0f;
    for (uint32_t p = 0; p < kPixels; ++p) {
      const float x = kEdge - span + 2 * span * p / (kPixels - 1);
      u.push_back(x);
      pos.insert(pos.end(), {x / kMap, 20.3f / kMap, 0.5f});
      nrm.insert(nrm.end(), {0, 0, 1, 1});
    }
    g.position = runtime.upload(pos);
    g.normal = runtime.upload(nrm);
    map = runtime.upload(depth);
    runtime.finish();  // the uploads read these vectors asynchronously
  }

  // By default the light travels along -z: the receivers (normal +z) face it.
  std::vector<float> run(const PcfParams& params, uint32_t pixels = kPixels,
                         glm::vec3 direction = {0, 0, -1}) {
    Light light;
    light.direction = direction;
    ShadowMapSettings s;
    s.size = kMap;
    s.bias_constant = 0;
    s.bias_slope = 0;
    Timeline t;
    const cl::Buffer& vis = pcf.run(g, pixels, kPixels, {{ViewSetup{}, &map}}, light, s, params, t);
    std::vector<float> out(pixels);
    runtime.read(vis, out.data(), out.size() * sizeof(float));
    return out;
  }
};

TEST(Pcf, BilinearGivesTheOneTexelRamp) {
  Fixture f(3.0f);
  const std::vector<float> vis = f.run({PcfParams::Mode::kBilinear});
  double err = 0;
  for (uint32_t p = 0; p < kPixels; ++p)
    err = std::max(err, std::abs(vis[p] - std::clamp(double(f.u[p]) - kEdge + 0.5, 0.0, 1.0)));
  std::printf("bilinear PCF vs ramp: max error %.3g\n", err);
  EXPECT_LT(err, 1e-5);
}

// A side edge-on to the light gets none of it (attached shadows), under both PCF modes, even
// where the map would light it (the hard test shares the set-up: attached_shadow_test.cpp).
TEST(Pcf, ASideEdgeOnToTheLightIsDark) {
  Fixture f(3.0f);
  for (PcfParams::Mode mode : {PcfParams::Mode::kBilinear, PcfParams::Mode::kPoisson}) {
    const std::vector<float> vis = f.run({mode}, kPixels, {0, -1, 0});
    for (float v : vis) ASSERT_EQ(v, 0.0f) << int(mode);
  }
}

TEST(Pcf, PoissonCountsTheTapsPastTheEdge) {
  for (uint32_t taps : {1u, 16u, 64u}) {
    Fixture f(5.0f);
    const float radius = 4.0f;
    const std::vector<float> vis = f.run({PcfParams::Mode::kPoisson, taps, radius, false});
    const std::vector<glm::vec2> disk = poisson_disk(taps);
    int mismatches = 0;
    for (uint32_t p = 0; p < kPixels; ++p) {
      int lit = 0;
      for (const glm::vec2& t : disk) lit += std::floor(f.u[p] + radius * t.x) >= kEdge;
      // A tap exactly on the edge may round either way in float.
      if (std::abs(vis[p] - float(lit) / taps) > 1e-6f) ++mismatches;
    }
    std::printf("Poisson PCF %u taps: %d of %u pixels differ from the CPU replay\n", taps,
                mismatches, kPixels);
    EXPECT_LE(mismatches, 2);
  }
}

TEST(Pcf, RotatedPoissonFollowsTheDiskAreaRamp) {
  Fixture f(5.0f);
  const float radius = 4.0f;
  const std::vector<float> vis = f.run({PcfParams::Mode::kPoisson, 64, radius, true});
  double err = 0;
  for (uint32_t p = 0; p < kPixels; ++p) {
    const double d = std::clamp((double(f.u[p]) - kEdge) / radius, -1.0, 1.0);
    const double lit = 1 - (std::acos(d) - d * std::sqrt(1 - d * d)) / M_PI;
    err = std::max(err, std::abs(vis[p] - lit));
  }
  std::printf("rotated 64-tap Poisson PCF vs disk-area ramp: max error %.3g\n", err);
  EXPECT_LT(err, 0.09);  // measured 0.078: the sampling error of 64 taps
}

// AUTO's trial tests a map hard and bilinear 2x2 in one launch (PCF_EDGE, EdgeSamplingPass): each
// pixel's value is bit for bit |hard - bilinear| of the two passes run apart, NaN where nothing
// is seen, and the mean is theirs. On the flat ramp, and on a receiver tilted against the map
// (a receiver plane, slope bias and constant bias in play), across the edge.
TEST(Pcf, EdgeModeIsHardMinusBilinearBitForBit) {
  for (bool tilted : {false, true}) {
    Fixture f(3.0f);
    std::vector<float> pos, nrm;
    for (uint32_t p = 0; p < kPixels; ++p) {
      const float x = f.u[p] / kMap, z = tilted ? 0.3f + 0.4f * x : 0.5f;
      if (p % 97 == 0)  // the sky: nothing seen
        pos.insert(pos.end(), {NAN, NAN, NAN});
      else
        pos.insert(pos.end(), {x, 20.3f / kMap, z});
      nrm.insert(nrm.end(), {tilted ? -0.37139f : 0.0f, 0, tilted ? 0.92848f : 1.0f, 1});
    }
    f.g.position = f.runtime.upload(pos);
    f.g.normal = f.runtime.upload(nrm);
    f.runtime.finish();
    Light light;
    light.direction = {0, 0, -1};
    ShadowMapSettings s;
    s.size = kMap;
    s.bias_constant = 1e-3f;
    s.bias_slope = 2.0f;
    const std::vector<LightMap> maps = {{ViewSetup{}, &f.map}};
    ShadowTestPass hard_pass(f.runtime, f.kernels);
    EdgeSamplingPass edge(f.runtime, f.kernels);
    Timeline t;
    std::vector<float> hard(kPixels), bilinear(kPixels), difference(kPixels);
    f.runtime.read(hard_pass.run(f.g, kPixels, maps, light, s, t), hard.data(), kPixels * 4);
    f.runtime.read(f.pcf.run(f.g, kPixels, kPixels, maps, light, s, {}, t), bilinear.data(),
                   kPixels * 4);
    const double mean = edge.run(f.g, kPixels, 1, maps, light, s, t);
    f.runtime.read(edge.difference(), difference.data(), kPixels * 4);
    double sum = 0;
    size_t seen = 0, soft = 0;
    for (uint32_t p = 0; p < kPixels; ++p) {
      if (std::isnan(hard[p])) {
        EXPECT_TRUE(std::isnan(difference[p])) << p;
        continue;
      }
      const float want = std::abs(hard[p] - bilinear[p]);
      EXPECT_EQ(difference[p], want) << tilted << " " << p;
      sum += want, ++seen, soft += want > 0;
    }
    EXPECT_GT(soft, 100u) << tilted;  // the ramp's texel: ~1/6 of the pixels
    EXPECT_NEAR(mean, sum / double(seen), 1e-6 * sum / double(seen)) << tilted;
  }
}

// The kernel works on strips of 64 pixels (the last one shifted back over its neighbour): images
// under one strip and the shifted strip give each pixel the result it has in a larger image.
TEST(Pcf, SmallImagesMatchTheLargeOne) {
  Fixture f(5.0f);
  for (PcfParams params : {PcfParams{PcfParams::Mode::kPoisson, 64, 4.0f, true},
                           PcfParams{PcfParams::Mode::kBilinear}}) {
    const std::vector<float> all = f.run(params);
    for (uint32_t pixels : {1u, 40u, 64u, 100u}) {
      const std::vector<float> part = f.run(params, pixels);
      for (uint32_t p = 0; p < pixels; ++p) EXPECT_EQ(part[p], all[p]) << pixels << " " << p;
    }
  }
}

// A cube goes to the kernel in one launch: each face's matrix and map, the faces not rendered
// with their zero matrix (their pixels lie off every map: lit) and the empty map, never read.
TEST(MapLookup, CubeFacesTakeTheirOwnMapsAndMatrices) {
  const cl::Buffer plus_y, minus_z, empty;
  std::vector<LightMap> maps(3);
  maps[0].setup.faces.owned = 1u << 2, maps[0].depth = &plus_y, maps[0].version = 7;
  maps[0].setup.world_to_ndc = glm::dmat4(2.0);
  maps[1].setup.faces.owned = 1u << 5, maps[1].depth = &minus_z, maps[1].version = 3;
  maps[1].setup.world_to_ndc = glm::dmat4(5.0);
  maps[2].setup.faces.owned = 0b011011u, maps[2].depth = &empty;  // not rendered
  maps[2].setup.world_to_ndc = glm::dmat4(0.0);
  const MapLookup m = map_lookup(maps, Light{}, ShadowMapSettings{});
  EXPECT_STREQ(m.option, "-DCUBE_FACES");
  EXPECT_EQ(m.maps[2], &plus_y);
  EXPECT_EQ(m.maps[5], &minus_z);
  EXPECT_EQ(m.cube.to_ndc[2], glm::mat4(2.0f));
  EXPECT_EQ(m.cube.to_ndc[5], glm::mat4(5.0f));
  for (int k : {0, 1, 3, 4}) {
    EXPECT_EQ(m.maps[k], &empty) << k;
    EXPECT_EQ(m.cube.to_ndc[k], glm::mat4(0.0f)) << k;
  }
  // Nothing rendered: still a cube, every face off the map.
  maps[2].setup.faces.owned = 0b111111u;
  const MapLookup none = map_lookup({maps[2]}, Light{}, ShadowMapSettings{});
  EXPECT_STREQ(none.option, "-DCUBE_FACES");
  for (const cl::Buffer* b : none.maps) EXPECT_EQ(b, &empty);
  // A face no map owns is a bug upstream, not a lit face.
  maps[2].setup.faces.owned = 0b011011u;
  EXPECT_THROW(map_lookup({maps[0], maps[2]}, Light{}, ShadowMapSettings{}), std::logic_error);
  // A single map (owned = 0) decides every pixel itself.
  LightMap single;
  single.depth = &plus_y;
  single.setup.world_to_ndc = glm::dmat4(3.0);
  const MapLookup one = map_lookup({single}, Light{}, ShadowMapSettings{});
  EXPECT_STREQ(one.option, "");
  EXPECT_EQ(one.lookup.to_ndc, glm::mat4(3.0f));
  for (const cl::Buffer* b : one.maps) EXPECT_EQ(b, &plus_y);
}

TEST(PoissonDisk, PointsAreInTheDiskAndSpread) {
  for (uint32_t n : {1u, 8u, 32u, 64u}) {
    const auto pts = poisson_disk(n);
    ASSERT_EQ(pts.size(), n);
    float closest = 2;
    for (size_t i = 0; i < n; ++i) {
      EXPECT_LE(glm::length(pts[i]), 1.0f);
      for (size_t j = 0; j < i; ++j) closest = std::min(closest, glm::distance(pts[i], pts[j]));
    }
    if (n > 1) {
      EXPECT_GT(closest, 0.5f * std::sqrt(3.14159f / (n * 0.866f))) << n;
    }
  }
}

}  // namespace
}  // namespace shadow
