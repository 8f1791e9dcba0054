// The atlas filters' footprint (seed 004's l_lod, eq. 4-5, as an ellipse) against the light's
// own view of the atlas, in double: on a 10 m plane whose UVs are a known scale of its
// coordinates, lit by a spot light at a slant (so the footprint stretches and turns across the
// plane), the disk of radius r around a map texel covers, in the atlas, the ellipse J D(r) with
// J = d(atlas texel) / d(map texel), taken here by central differences of the UVs the light sees
// at neighbouring map texels, and D the disk in map texels (r times the map's texels per light
// unit). The kernel instead maps the atlas texel's axes on the surface through the light's
// Jacobian there and inverts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/light_space.hpp"
#include "engine/passes/atlas.hpp"
#include "engine/passes/atlas_soften.hpp"
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

// The lights: a spot west of the plane and above it, looking down across it; a sun low in the
// west, its map turned about its axis and wider than high (texels per world
// unit differ along u and v), as a fitted map may be.
struct LitBy {
  Light light;
  ViewSetup setup;
};
LitBy spot_light() {
  LitBy l;
  l.light.type = LightType::kSpot;
  l.light.position = {-8, 6, 2};
  l.light.direction = glm::normalize(glm::vec3(10, -6, -3));
  l.light.cone_angle_deg = 100;
  l.setup.view = glm::lookAt(glm::dvec3(-8, 6, 2), glm::dvec3(2, 0, -1), glm::dvec3(0, 1, 0));
  l.setup.world_to_ndc =
      gl_to_texture_ndc() * glm::perspective(glm::radians(100.0), 1.0, 0.5, 40.0) * l.setup.view;
  return l;
}
LitBy low_sun(double elevation_deg) {
  LitBy l;
  l.light.type = LightType::kDirectional;
  const glm::dvec3 d = glm::normalize(glm::dvec3(std::cos(glm::radians(elevation_deg)),
                                                 -std::sin(glm::radians(elevation_deg)), 0.3));
  l.light.direction = glm::vec3(d);
  l.light.size = 2;
  l.setup.view = glm::lookAt(-20.0 * d, glm::dvec3(0), glm::normalize(glm::dvec3(0.3, 1, 0.2)));
  l.setup.world_to_ndc =
      gl_to_texture_ndc() * glm::ortho(-9.0, 9.0, -6.0, 6.0, 1.0, 40.0) * l.setup.view;
  return l;
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

// The ellipse of the disk of radius `radius` (light units) in the atlas around the map texel
// that sees x, as S = (xx, yy, xy) with the ellipse {p : p^T S^-1 p <= 1} in atlas texels.
glm::dvec3 rendered_footprint(const glm::dmat4& m, const glm::dmat4& inverse, const glm::dvec3& x,
                              glm::dvec2 scale, double radius) {
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
  // Atlas texels per light unit: A = J diag(scale), columns ds and dt; S = r^2 A A^T.
  const glm::dvec2 a0 = ds * scale.x * radius, a1 = dt * scale.y * radius;
  return {a0.x * a0.x + a1.x * a1.x, a0.y * a0.y + a1.y * a1.y, a0.x * a0.y + a1.x * a1.y};
}

// The footprint's long semi-axis at most 8 times its short one (atlas_soften.cl's capped_stretch).
constexpr double kMaxStretch = 8;
glm::dvec3 capped(const glm::dvec3& S) {
  const double mean = 0.5 * (S.x + S.y), d = std::hypot(0.5 * (S.x - S.y), S.z);
  const double big = mean + d, small = mean - d, cap = kMaxStretch * kMaxStretch * small;
  if (big <= cap) return S;
  const double f = (cap - small) / (big - small);
  return {small + (S.x - small) * f, small + (S.y - small) * f, S.z * f};
}

// The long over the short semi-axis.
double stretch(const glm::dvec3& S) {
  const double mean = 0.5 * (S.x + S.y), d = std::hypot(0.5 * (S.x - S.y), S.z);
  return std::sqrt((mean + d) / (mean - d));
}

// Compares every texel's footprint with the light's disk in the atlas, capped; returns the most
// the disk stretched before the cap.
double expect_footprints(const LitBy& lit, const char* name) {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  AtlasPass atlas{runtime, kernels};
  AtlasSoftenPass soften{runtime, kernels};
  Timeline timeline;
  const Scene scene = plane();
  SceneBuffers buffers(runtime, kernels, scene, timeline);
  AtlasSettings settings;
  settings.tile = kTile;
  const GBuffer& view = atlas.bake(scene, buffers, settings, timeline);
  const uint32_t texels = atlas.width() * atlas.height();
  EXPECT_EQ(texels, kTile * kTile);

  const ViewSetup& setup = lit.setup;
  ShadowMapSettings map;
  map.size = kMapSize;
  const glm::dvec2 scale(pcss_geometry(setup, lit.light, kMapSize).scale);
  const float radius = 4.0f / float(scale.x);  // about 4 map texels: above the half-texel floor
  cl::Buffer everywhere;                       // a penumbra at every texel: a footprint everywhere
  runtime.ensure(everywhere, size_t{texels} * sizeof(float));
  uint32_t bits;
  std::memcpy(&bits, &radius, sizeof bits);
  runtime.fill(everywhere, bits);
  const cl::Buffer& footprint = soften.footprint(view, atlas.texel_axes(), everywhere, texels,
                                                 setup, lit.light, map, timeline);
  std::vector<float> got(size_t{texels} * 3);
  runtime.read(footprint, got.data(), got.size() * sizeof(float));

  const glm::dmat4 inverse = glm::inverse(setup.world_to_ndc);
  double worst = 0, most_seen = 0, most_kept = 0;
  uint32_t compared = 0;
  for (uint32_t j = 0; j < kTile; ++j)
    for (uint32_t i = 0; i < kTile; ++i) {
      const double u = (i + 0.5) / kTile, v = (j + 0.5) / kTile;
      const glm::dvec3 x(-kHalf + 2 * kHalf * u, 0.0, -kHalf + 2 * kHalf * v);
      const glm::dvec3 seen = rendered_footprint(setup.world_to_ndc, inverse, x, scale, radius);
      const glm::dvec3 want = capped(seen);
      const float* s = &got[(size_t{j} * kTile + i) * 3];
      EXPECT_TRUE(std::isfinite(s[0]) && std::isfinite(s[1]) && std::isfinite(s[2]))
          << i << ", " << j;
      // Relative to the ellipse's size: the difference of the two matrices over the larger
      // eigenvalue, which bounds it.
      const double mean = 0.5 * (want.x + want.y), d = std::hypot(0.5 * (want.x - want.y), want.z);
      const double diff =
          std::max({std::abs(s[0] - want.x), std::abs(s[1] - want.y), std::abs(s[2] - want.z)});
      worst = std::max(worst, diff / (mean + d));
      most_seen = std::max(most_seen, stretch(seen));
      most_kept = std::max(most_kept, stretch(glm::dvec3(s[0], s[1], s[2])));
      ++compared;
    }
  std::printf(
      "[ atlas    ] %s: footprints of %u texels: the disk stretched up to %.2f to 1, kept up to "
      "%.2f; worst relative difference %.2g\n",
      name, compared, most_seen, most_kept, worst);
  EXPECT_LT(worst, 1e-4);  // measured: 1.2e-5
  EXPECT_LT(most_kept, kMaxStretch * (1 + 1e-4));
  return most_seen;
}

TEST(AtlasFootprint, IsTheSpotsDiskSeenInTheAtlas) {
  EXPECT_GT(expect_footprints(spot_light(), "spot"), 2.0);  // the slant stretches the disk
}

TEST(AtlasFootprint, IsALowSunsDiskSeenInTheAtlas) {
  EXPECT_GT(expect_footprints(low_sun(20), "sun 20 degrees up"), 2.0);
}

TEST(AtlasFootprint, AGrazingSunsDiskStretchesNoMoreThanTheCap) {
  EXPECT_GT(expect_footprints(low_sun(3), "sun 3 degrees up"), 2 * kMaxStretch);
}

}  // namespace
}  // namespace shadow
