// Area-light visibility against closed forms: a half-plane occluder's penumbra under a disk light
// (spot and directional) and a disk occluder's partial eclipse under a point light.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "oracle/area_light.hpp"
#include "oracle/scenes.hpp"

namespace shadow::oracle {
namespace {

using scenes::add;

// A one-sided quad y = h over [x0, x1] x [z0, z1], facing +y.
Mesh y_quad(float h, float x0, float x1, float z0, float z1) {
  Mesh m;
  m.positions = {x0, h, z0, x1, h, z0, x1, h, z1, x0, h, z1};
  m.indices = {0, 2, 1, 0, 3, 2};
  return m;
}

// A regular n-gon of circumradius r in the plane y = h, centred on the y axis.
Mesh y_disk(float h, float r, uint32_t n) {
  Mesh m;
  m.positions = {0.0f, h, 0.0f};
  for (uint32_t k = 0; k < n; ++k) {
    const double a = 2.0 * std::numbers::pi * k / n;
    m.positions.insert(m.positions.end(), {static_cast<float>(r * std::cos(a)), h,
                                           static_cast<float>(r * std::sin(a))});
    m.indices.insert(m.indices.end(), {0, 1 + (k + 1) % n, 1 + k});
  }
  return m;
}

// Fraction of a unit-radius disk with x >= u (u in units of the radius).
double disk_fraction_beyond(double u) {
  u = std::clamp(u, -1.0, 1.0);
  return (std::acos(u) - u * std::sqrt(1.0 - u * u)) / std::numbers::pi;
}

struct Errors {
  double max = 0.0, mean = 0.0;
};

// Samples ground points (x, 0, 0.3) across the penumbra and compares with closed_form(x).
template <typename ClosedForm>
Errors penumbra_errors(const Scene& scene, const Light& light, double half_width,
                       ClosedForm closed_form, const AreaLightOptions& options = {}) {
  RayOracle oracle(scene);
  std::vector<glm::dvec3> points, normals;
  const int n = 201;
  for (int k = 0; k < n; ++k) {
    points.push_back({half_width * (2.0 * k / (n - 1) - 1.0), 0.0, 0.3});
    normals.push_back({0.0, 1.0, 0.0});
  }
  const AreaVisibility v = area_visibility(oracle, light, points, normals, {}, options);
  EXPECT_EQ(v.unconverged, 0u);
  Errors e;
  for (int k = 0; k < n; ++k) {
    const double err = std::abs(v.visibility[k] - closed_form(points[k].x));
    e.max = std::max(e.max, err);
    e.mean += err / n;
  }
  std::printf("max error %.4f, mean %.5f, %.1f rays per point\n", e.max, e.mean,
              static_cast<double>(v.rays) / n);
  return e;
}

Scene half_plane_scene(float h) {
  Scene scene;
  add(scene, y_quad(0.0f, -50, 50, -50, 50), glm::mat4(1.0f));
  add(scene, y_quad(h, -50, 0, -50, 50), glm::mat4(1.0f));  // edge along z at x = 0
  return scene;
}

TEST(AreaLight, HalfPlaneUnderSpotDiskMatchesClosedForm) {
  // Disk of radius R at height H facing down; edge at height h. A ground point at x sees the
  // occluder cover the light's x < x (1 - H / h): visible = segment fraction beyond that line.
  const double H = 10.0, h = 5.0, R = 1.0;
  Light light;
  light.type = LightType::kSpot;
  light.position = {0.0f, static_cast<float>(H), 0.0f};
  light.direction = {0.0f, -1.0f, 0.0f};
  light.cone_angle_deg = 120.0f;
  light.size = static_cast<float>(R);
  const double width = R * h / (H - h);  // penumbra half-width on the ground
  const Errors e =
      penumbra_errors(half_plane_scene(static_cast<float>(h)), light, 1.5 * width,
                      [&](double x) { return disk_fraction_beyond(x * (1 - H / h) / R); });
  EXPECT_LT(e.max, 0.01);    // the tolerance; measured 0.0042
  EXPECT_LT(e.mean, 0.003);  // measured 0.0010
}

TEST(AreaLight, HalfPlaneUnderDirectionalDiskMatchesClosedForm) {
  // A sun of angular diameter 2a straight overhead; to-light directions (ox, 1, oz) with
  // |(ox, oz)| <= tan a. Blocked where x + ox h < 0.
  const double h = 2.0, a = glm::radians(5.0);
  Light light;
  light.direction = {0.0f, -1.0f, 0.0f};
  light.size = 10.0f;
  const Errors e =
      penumbra_errors(half_plane_scene(static_cast<float>(h)), light, 1.5 * h * std::tan(a),
                      [&](double x) { return disk_fraction_beyond(-x / (h * std::tan(a))); });
  EXPECT_LT(e.max, 0.01);    // the tolerance; measured 0.0050
  EXPECT_LT(e.mean, 0.003);  // measured 0.0013
}

TEST(AreaLight, DiskOccluderEclipsesPointLightByProjectedArea) {
  // Points straight below a polygon occluder (area A at height h) under a spherical light of
  // radius R at height H: the polygon's shadow on the light's disk has area A (H / h)^2.
  const double H = 8.0, h = 2.0, R = 1.5, r = 0.25;
  const uint32_t sides = 64;
  Scene scene;
  add(scene, y_quad(0.0f, -50, 50, -50, 50), glm::mat4(1.0f));
  add(scene, y_disk(static_cast<float>(h), static_cast<float>(r), sides), glm::mat4(1.0f));
  const double area = 0.5 * sides * r * r * std::sin(2.0 * std::numbers::pi / sides);
  Light light;
  light.type = LightType::kPoint;
  light.position = {0.0f, static_cast<float>(H), 0.0f};
  light.size = static_cast<float>(R);
  RayOracle oracle(scene);
  // Shadow rays start above the ground by the oracle's normal offset.
  const double y0 =
      std::max(AreaLightOptions{}.offset_scale * oracle.scene_diagonal(), oracle.min_ray_offset());
  const double scale = (H - y0) / (h - y0);
  const double expected = 1.0 - area * scale * scale / (std::numbers::pi * R * R);
  std::vector<glm::dvec3> points(256, glm::dvec3(0.0)), normals(256, glm::dvec3(0, 1, 0));
  AreaLightOptions options;
  for (size_t k = 0; k < points.size(); ++k) points[k].z = 1e-4 * k;  // distinct sample streams
  const AreaVisibility v = area_visibility(oracle, light, points, normals, {}, options);
  double max_error = 0.0;
  for (float x : v.visibility) max_error = std::max(max_error, std::abs(x - expected));
  std::printf("expected %.4f, max error %.4f\n", expected, max_error);
  EXPECT_LT(max_error, 0.01);  // the tolerance; measured 0.0076
}

TEST(AreaLight, ZeroSizeEqualsHardVisibility) {
  scenes::Setup s = scenes::test_scene();
  s.camera.width = 320;
  s.camera.height = 180;
  RayOracle oracle(s.scene);
  const AreaVisibility soft = camera_area_visibility(oracle, s.camera, s.light);
  const std::vector<float> hard = oracle.camera_visibility(s.camera, s.light);
  ASSERT_EQ(soft.visibility.size(), hard.size());
  size_t differ = 0, shadowed = 0;
  for (size_t i = 0; i < hard.size(); ++i) {
    if (std::isnan(hard[i])) {
      EXPECT_TRUE(std::isnan(soft.visibility[i]));
      continue;
    }
    differ += soft.visibility[i] != hard[i];
    shadowed += hard[i] == 0.0f;
  }
  std::printf("%zu shadowed pixels, %zu differ\n", shadowed, differ);
  EXPECT_GT(shadowed, 100u);
  EXPECT_EQ(differ, 0u);
}

TEST(AreaLight, SquareToDiskKeepsStrataInsideAndEqualArea) {
  // Corners of the square go to the rim, the centre to the centre; every stratum of a g x g
  // grid covers pi / g^2 of the disk.
  EXPECT_NEAR(glm::length(square_to_disk({1.0, 1.0})), 1.0, 1e-12);
  EXPECT_NEAR(glm::length(square_to_disk({0.5, 0.5})), 0.0, 1e-12);
  const int g = 64;
  double worst = 0.0;
  for (int j = 0; j < g; ++j) {
    for (int i = 0; i < g; ++i) {
      // The stratum's mapped boundary as a fine polygon (its edges are arcs and spirals).
      std::vector<glm::dvec2> ring;
      const int m = 16;
      const glm::dvec2 c[5] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
      for (int e = 0; e < 4; ++e) {
        for (int k = 0; k < m; ++k) {
          const glm::dvec2 q = c[e] + (c[e + 1] - c[e]) * (double(k) / m);
          ring.push_back(square_to_disk({(i + q.x) / g, (j + q.y) / g}));
        }
      }
      double area = 0.0;
      for (size_t k = 0; k < ring.size(); ++k) {
        const glm::dvec2 a = ring[k], b = ring[(k + 1) % ring.size()];
        area += 0.5 * (a.x * b.y - a.y * b.x);
      }
      worst = std::max(worst, std::abs(std::abs(area) * g * g / std::numbers::pi - 1.0));
    }
  }
  std::printf("worst stratum area error %.4f\n", worst);
  EXPECT_LT(worst, 0.002);  // measured 0.0004 (polygon vs true boundary)
}

}  // namespace
}  // namespace shadow::oracle
