// The atlas filters' level correction l_lod (seed 004, eq. 4-5) against the paper's own way of
// getting it, emulated in double: render, from the light, the atlas texture whose mip levels hold
// their own level, so that each map texel reads the level its footprint covers in the atlas. On
// a 10 m plane whose UVs are a known scale of its coordinates, lit by a spot light at a slant
// (so the level changes across the plane), that level is 0.5 log2 |det d(atlas texel) / d(map
// texel)|, taken here by central differences of the UVs the light sees at neighbouring map
// texels. The kernel instead divides two world areas from Jacobians at the atlas texel.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/light_space.hpp"
#include "engine/passes/atlas.hpp"
#include "engine/passes/pcss.hpp"
#include "engine/plan/atlas_layout.hpp"

namespace shadow {
namespace {

constexpr double kHalf = 5;  // the plane is [-5, 5]^2 at y = 0
constexpr uint32_t kTile = 256, kMapSize = 1024;

// The plane as two triangles with u = (x + 5) / 10, v = (z + 5) / 10.
Scene plane() {
  Mesh m;
  m.positions = {-5, 0, -5, 5, 0, -5, 5, 0, 5, -5, 0, 5};
  m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  m.indices = {0, 2, 1, 0, 3, 2};
  Scene s;
  s.meshes = {m};
  s.instances = {Instance{0}};
  return s;
}

// The spot light's world -> texture NDC: west of the plane and above it, looking down across it.
glm::dmat4 light_matrix() {
  const glm::dmat4 view =
      glm::lookAt(glm::dvec3(-8, 6, 2), glm::dvec3(2, 0, -1), glm::dvec3(0, 1, 0));
  return gl_to_texture_ndc() * glm::perspective(glm::radians(100.0), 1.0, 0.5, 40.0) * view;
}

// The world point of the plane that map texel coordinates (s, t) see.
glm::dvec3 seen_at(const glm::dmat4& inverse, double s, double t) {
  const auto unproject = [&](double z) {
    const glm::dvec4 h = inverse * glm::dvec4(s / kMapSize, t / kMapSize, z, 1.0);
    return glm::dvec3(h) / h.w;
  };
  const glm::dvec3 a = unproject(0.0), b = unproject(1.0);
  return a + (b - a) * (a.y / (a.y - b.y));  // where the ray meets y = 0
}

// The level the rendered level texture holds at the map texel that sees x: the mip level of the
// atlas covered by one map texel's footprint (isotropic: the square root of the area ratio).
double rendered_level(const glm::dmat4& m, const glm::dmat4& inverse, const glm::dvec3& x) {
  const glm::dvec4 c = m * glm::dvec4(x, 1.0);
  const double s = c.x / c.w * kMapSize, t = c.y / c.w * kMapSize, h = 0.5;
  // Atlas texel coordinates of a world point of the plane.
  const auto texel = [](const glm::dvec3& p) {
    return glm::dvec2((p.x + kHalf) / (2 * kHalf), (p.z + kHalf) / (2 * kHalf)) * double(kTile);
  };
  const glm::dvec2 ds =
      (texel(seen_at(inverse, s + h, t)) - texel(seen_at(inverse, s - h, t))) / (2 * h);
  const glm::dvec2 dt =
      (texel(seen_at(inverse, s, t + h)) - texel(seen_at(inverse, s, t - h))) / (2 * h);
  return 0.5 * std::log2(std::abs(ds.x * dt.y - ds.y * dt.x));
}

TEST(AtlasLevel, MatchesTheRenderedLevelTexture) {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  AtlasPass atlas{runtime, kernels};
  PcssPass pcss{runtime, kernels};
  Timeline timeline;
  const Scene scene = plane();
  SceneBuffers buffers(runtime, kernels, scene, timeline);
  AtlasSettings settings;
  settings.tile = kTile;
  const GBuffer& view = atlas.bake(scene, buffers, settings, timeline);
  const uint32_t texels = atlas.width() * atlas.height();
  ASSERT_EQ(texels, kTile * kTile);

  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {-8, 6, 2};
  spot.direction = glm::normalize(glm::vec3(10, -6, -3));
  spot.cone_angle_deg = 100;
  ViewSetup setup;
  setup.world_to_ndc = light_matrix();
  ShadowMapSettings map;
  map.size = kMapSize;
  cl::Buffer everywhere;  // a penumbra at every texel: l_lod everywhere
  runtime.ensure(everywhere, size_t{texels} * sizeof(float));
  runtime.fill(everywhere, 0x3f800000u);  // 1.0f
  const cl::Buffer& level =
      pcss.atlas_level(view, atlas.texel_area(), everywhere, texels, setup, spot, map, timeline);
  std::vector<float> got(texels);
  runtime.read(level, got.data(), got.size() * sizeof(float));

  const glm::dmat4 inverse = glm::inverse(setup.world_to_ndc);
  double worst = 0, lowest = 1e9, highest = -1e9;
  uint32_t compared = 0;
  for (uint32_t j = 0; j < kTile; ++j)
    for (uint32_t i = 0; i < kTile; ++i) {
      const double u = (i + 0.5) / kTile, v = (j + 0.5) / kTile;
      const glm::dvec3 x(-kHalf + 2 * kHalf * u, 0.0, -kHalf + 2 * kHalf * v);
      const double want = rendered_level(setup.world_to_ndc, inverse, x);
      const float l = got[size_t{j} * kTile + i];
      ASSERT_TRUE(std::isfinite(l)) << i << ", " << j;
      worst = std::max(worst, std::abs(double(l) - want));
      lowest = std::min(lowest, want), highest = std::max(highest, want);
      ++compared;
    }
  std::printf("[ atlas    ] l_lod over %u texels: %.2f .. %.2f levels; worst difference %.2g\n",
              compared, lowest, highest, worst);
  EXPECT_GT(highest - lowest, 2.5);  // the slant spans levels: -1.99 .. 0.57
  EXPECT_LT(worst, 1e-3);            // measured
}

}  // namespace
}  // namespace shadow
