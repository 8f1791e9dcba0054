// The oracle against closed forms: if these fail, no accuracy figure built on it means anything.
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/scenes.hpp"

namespace shadow::oracle {
namespace {

using scenes::add;
using scenes::box_mesh;
using scenes::grid_mesh;
using scenes::trs;

// A matrix given by its rows (the GLM constructor takes columns).
glm::dmat4 rows(glm::dvec4 r0, glm::dvec4 r1, glm::dvec4 r2, glm::dvec4 r3) {
  return glm::transpose(glm::dmat4(r0, r1, r2, r3));
}

// Clip-space [-1, 1]^2 (y up) -> [0, 1]^2 from the top-left corner; z untouched.
const glm::dmat4 kToTopLeft = rows({0.5, 0, 0, 0.5}, {0, -0.5, 0, 0.5}, {0, 0, 1, 0}, {0, 0, 0, 1});

// A single quad y = h(x, z) = a x + b z + c over [x0, x1] x [z0, z1].
Mesh tilted_quad(double a, double b, double c, double x0, double x1, double z0, double z1) {
  Mesh m;
  for (auto [x, z] : {std::pair{x0, z0}, {x1, z0}, {x1, z1}, {x0, z1}}) {
    m.positions.insert(
        m.positions.end(),
        {static_cast<float>(x), static_cast<float>(a * x + b * z + c), static_cast<float>(z)});
  }
  m.indices = {0, 2, 1, 0, 3, 2};
  return m;
}

// A quad in the plane z = z over [x0, x1] x [y0, y1], exact in float.
Mesh z_quad(float z, float x0, float x1, float y0, float y1) {
  Mesh m;
  m.positions = {x0, y0, z, x1, y0, z, x1, y1, z, x0, y1, z};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// Orthographic map looking straight down over x, z in [-10, 10]; texel rows run along +z;
// NDC z = (10 - y) / 20.
const glm::dmat4 kDownOrtho =
    rows({1.0 / 20, 0, 0, 0.5}, {0, 0, 1.0 / 20, 0.5}, {0, -1.0 / 20, 0, 0.5}, {0, 0, 0, 1});

TEST(OracleDepth, OrthographicTiltedPlaneMatchesAnalyticDepth) {
  // Quad corners in float: choose coefficients exact in binary so the float mesh is the plane.
  const double a = 0.25, b = -0.125, c = 1.5;
  Scene scene;
  add(scene, tilted_quad(a, b, c, -16, 16, -16, 16), glm::mat4(1.0f));
  RayOracle oracle(scene);
  const uint32_t n = 256;
  const auto depth = oracle.shadow_map_depth(kDownOrtho, n);
  double max_err = 0.0;
  for (uint32_t j = 0; j < n; ++j) {
    for (uint32_t i = 0; i < n; ++i) {
      const double x = -10.0 + 20.0 * (i + 0.5) / n, z = -10.0 + 20.0 * (j + 0.5) / n;
      const double expected = (10.0 - (a * x + b * z + c)) / 20.0;
      max_err = std::max(max_err, std::abs(depth[j * n + i] - expected));
    }
  }
  EXPECT_LT(max_err, 1e-12);
}

TEST(OracleDepth, EmptyTexelsHoldOneAndOnlyCastersCount) {
  Scene scene;
  add(scene, tilted_quad(0, 0, 0, -16, 0, -16, 16), glm::mat4(1.0f));  // covers x < 0 only
  // A box above the middle of the left half that casts nothing: invisible to the map.
  add(scene, box_mesh(), trs({-5, 2, 0}, 0, {0, 1, 0}, {2, 2, 2}), /*casts=*/false);
  const uint32_t n = 64;
  auto depth = RayOracle(scene).shadow_map_depth(kDownOrtho, n);
  for (uint32_t j = 0; j < n; ++j) {
    for (uint32_t i = 0; i < n; ++i) {
      ASSERT_DOUBLE_EQ(depth[j * n + i], i < n / 2 ? 0.5 : 1.0) << i << "," << j;
    }
  }
  scene.instances[1].casts_shadows = true;
  depth = RayOracle(scene).shadow_map_depth(kDownOrtho, n);
  // Texel centre (-5.15625, 0.15625) lies inside the box's footprint [-6, -4] x [-1, 1]; its top
  // is at y = 3.
  EXPECT_NEAR(depth[(n / 2) * n + 15], (10.0 - 3.0) / 20.0, 1e-12);
}

// Spot-style perspective map (GLM right-handed, depth zero-to-one) of the ground y = 0.
TEST(OracleDepth, PerspectiveMapOfGroundMatchesAnalyticDepth) {
  const glm::dvec3 pos(0, 10, 0), target(8, 0, 6);
  const double fov = glm::radians(90.0), n_plane = 1.0, f_plane = 30.0;
  const glm::dmat4 view = glm::lookAtRH(pos, target, glm::dvec3(0, 1, 0));
  const glm::dmat4 m = kToTopLeft * glm::perspectiveRH_ZO(fov, 1.0, n_plane, f_plane) * view;
  Scene scene;
  add(scene, grid_mesh(4), trs({0, 0, 0}, 0, {0, 1, 0}, {200, 1, 200}));
  const uint32_t n = 200;
  const auto depth = RayOracle(scene).shadow_map_depth(m, n);

  // Independent closed form: the texel's view-space direction (x tan, y tan, -1) rotated to
  // world meets y = 0 at a parameter equal to its view depth t; NDC z = f/(f-n) (1 - n/t).
  const glm::dmat3 to_world = glm::transpose(glm::dmat3(view));
  const double tan_half = std::tan(fov / 2);
  double max_err = 0.0;
  size_t empty = 0;
  for (uint32_t j = 0; j < n; ++j) {
    for (uint32_t i = 0; i < n; ++i) {
      const double xn = 2.0 * (i + 0.5) / n - 1.0, yn = 1.0 - 2.0 * (j + 0.5) / n;
      const glm::dvec3 dir = to_world * glm::dvec3(xn * tan_half, yn * tan_half, -1.0);
      const double t = -pos.y / dir.y;
      double expected = 1.0;
      if (dir.y < 0 && t >= n_plane && t <= f_plane) {
        expected = f_plane / (f_plane - n_plane) * (1.0 - n_plane / t);
      }
      empty += expected == 1.0;
      max_err = std::max(max_err, std::abs(depth[j * n + i] - expected));
    }
  }
  EXPECT_LT(max_err, 1e-12);
  EXPECT_GT(empty, 100u);  // the far plane and the horizon cut the ground: both cases occur
  EXPECT_LT(empty, n * n / 2);
}

// A map whose NDC z range wraps through infinity: an orthographic light along the z axis of a
// camera's post-perspective space (as PSM builds), with depth range z_pp in [1.05, 5]. In front
// of the camera only view depths >= ~12.9 qualify; behind it, the line returns from infinity and
// view-space z >= ~0.59 qualifies. The segment between the unprojected z=0 and z=1 points is
// exactly the wrong part of the line.
TEST(OracleDepth, ProjectiveMapWrappingThroughInfinity) {
  const double n_plane = 1.0, f_plane = 10.0, z0 = 1.05, z1 = 5.0;
  const glm::dmat4 cam = glm::perspectiveRH_NO(glm::radians(60.0), 1.0, n_plane, f_plane) *
                         glm::lookAtRH(glm::dvec3(0), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0));
  const glm::dmat4 light = kToTopLeft * rows({1, 0, 0, 0}, {0, 1, 0, 0},
                                             {0, 0, 1 / (z1 - z0), -z0 / (z1 - z0)}, {0, 0, 0, 1});
  const glm::dmat4 m = light * cam;
  auto ndc_of_view_z = [&](double zv) {  // NO perspective, then the light's depth remap
    const double zpp =
        ((f_plane + n_plane) * zv + 2 * f_plane * n_plane) / (f_plane - n_plane) / zv;
    return (zpp - z0) / (z1 - z0);
  };
  Scene scene;
  add(scene, z_quad(3, -40, 40, -40, 40), glm::mat4(1.0f));  // behind the camera
  // In front at depth 20, covering x < 0 only: NDC z ~ 0.015 beats the plane behind.
  add(scene, z_quad(-20, -40, 0, -40, 40), glm::mat4(1.0f));
  // In front at depth 5, covering y > 0: z_pp ~ 0.78 lies outside [z0, z1], so it never counts.
  add(scene, z_quad(-5, -40, 40, 0, 40), glm::mat4(1.0f));
  RayOracle oracle(scene);
  const double behind = ndc_of_view_z(3.0), front = ndc_of_view_z(-20.0);
  ASSERT_GT(behind, 0.2);
  ASSERT_LT(front, 0.02);
  const uint32_t n = 32;
  const auto depth = oracle.shadow_map_depth(m, n);
  DepthOptions clipped;
  clipped.require_positive_w = true;
  const auto depth_w = oracle.shadow_map_depth(m, n, clipped);
  for (uint32_t j = 0; j < n; ++j) {
    for (uint32_t i = 0; i < n; ++i) {
      const bool left = i < n / 2;
      EXPECT_NEAR(depth[j * n + i], left ? front : behind, 1e-12) << i << "," << j;
      // Behind the camera clip w < 0: a clipping rasterizer never draws it.
      EXPECT_NEAR(depth_w[j * n + i], left ? front : 1.0, 1e-12) << i << "," << j;
    }
  }
}

// Slab test in double: does the ray p + s d (s > 0) meet the box [lo, hi]?
bool ray_meets_box(glm::dvec3 p, glm::dvec3 d, glm::dvec3 lo, glm::dvec3 hi) {
  double s0 = 0, s1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    double a = (lo[k] - p[k]) / d[k], b = (hi[k] - p[k]) / d[k];
    if (a > b) std::swap(a, b);
    s0 = std::max(s0, a);
    s1 = std::min(s1, b);
  }
  return s0 <= s1;
}

struct BoxOverGround : ::testing::Test {
  Scene scene;
  const glm::dvec3 lo{-1, 1, -1}, hi{1, 2, 1};  // the floating box
  void SetUp() override {
    add(scene, grid_mesh(8), trs({0, 0, 0}, 0, {0, 1, 0}, {40, 1, 40}));
    add(scene, box_mesh(), trs({0, 1.5f, 0}, 0, {0, 1, 0}, {2, 1, 2}));
  }
};

TEST_F(BoxOverGround, SunShadowFootprintIsTheBoxProjectedAlongTheLight) {
  Light sun;
  sun.type = LightType::kDirectional;
  sun.direction = glm::normalize(glm::vec3(0.5f, -1.0f, 0.3f));
  const glm::dvec3 to_sun = -glm::normalize(glm::dvec3(sun.direction));
  std::vector<glm::dvec3> points, normals;
  for (double z = -6; z <= 6; z += 0.05) {
    for (double x = -6; x <= 6; x += 0.05) {
      points.emplace_back(x, 0, z);
      normals.emplace_back(0, 1, 0);
    }
  }
  const auto vis = RayOracle(scene).hard_visibility(sun, points, normals);
  // Points within 1 mm of the footprint's edge are skipped: the origin offset (1e-6 of the
  // ~57 m scene diagonal, lifted along the normal) shifts the edge by ~0.03 mm.
  const glm::dvec3 margin(0.001);
  size_t checked = 0, shadowed = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const bool in_outer = ray_meets_box(points[i], to_sun, lo - margin, hi + margin);
    const bool in_inner = ray_meets_box(points[i], to_sun, lo + margin, hi - margin);
    if (in_outer != in_inner) continue;
    ++checked;
    shadowed += in_inner;
    ASSERT_EQ(vis[i], in_inner ? 0.0f : 1.0f) << points[i].x << "," << points[i].z;
  }
  EXPECT_GT(checked, points.size() * 95 / 100);
  EXPECT_GT(shadowed, 1000u);  // the footprint (~4-5 m^2 at 5 cm spacing) is really tested
}

TEST_F(BoxOverGround, NormalsTurnToTheLightAndNaNPointsStayNaN) {
  Light sun;
  sun.direction = glm::vec3(0, -1, 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Top face: lit. Bottom face (normal away from the sun): the offset ray starts inside the box
  // and meets its top from within, so shadowed. Ground under the box: shadowed. NaN: NaN.
  const std::vector<glm::dvec3> points = {{0.3, 2, 0.2}, {0.3, 1, 0.2}, {0.3, 0, 0.2}, {nan, 0, 0}};
  const std::vector<glm::dvec3> normals = {{0, 1, 0}, {0, -1, 0}, {0, 1, 0}, {0, 1, 0}};
  const auto vis = RayOracle(scene).hard_visibility(sun, points, normals);
  EXPECT_EQ(vis[0], 1.0f);
  EXPECT_EQ(vis[1], 0.0f);
  EXPECT_EQ(vis[2], 0.0f);
  EXPECT_TRUE(std::isnan(vis[3]));
}

TEST_F(BoxOverGround, SpotConePointLightAndShadowFlags) {
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0, 10, 0};
  spot.direction = {0, -1, 0};
  spot.cone_angle_deg = 60;  // edge of the cone meets the ground at r = 10 tan 30 = 5.77
  const std::vector<glm::dvec3> points = {{5.5, 0, 0}, {0, 0, 6}, {0.1, 0, 0.1}, {3, 11, 0}};
  const std::vector<glm::dvec3> normals(points.size(), glm::dvec3(0, 1, 0));
  RayOracle oracle(scene);
  auto vis = oracle.hard_visibility(spot, points, normals);
  EXPECT_EQ(vis[0], 1.0f);  // inside the cone
  EXPECT_EQ(vis[1], 0.0f);  // outside it
  EXPECT_EQ(vis[2], 0.0f);  // under the box
  EXPECT_EQ(vis[3], 0.0f);  // behind the light

  Light point = spot;
  point.type = LightType::kPoint;
  vis = oracle.hard_visibility(point, points, normals);
  EXPECT_EQ(vis[1], 1.0f);  // no cone
  EXPECT_EQ(vis[2], 0.0f);
  EXPECT_EQ(vis[3], 1.0f);  // a point light shines upwards too

  const std::vector<uint8_t> receives = {1, 1, 0, 1};
  vis = oracle.hard_visibility(spot, points, normals, receives);
  EXPECT_EQ(vis[2], 1.0f);  // a non-receiver ignores the box
  EXPECT_EQ(vis[1], 0.0f);  // but not the cone

  scene.instances[1].casts_shadows = false;
  vis = RayOracle(scene).hard_visibility(spot, points, normals);
  EXPECT_EQ(vis[2], 1.0f);  // a non-caster shadows nothing
}

TEST(OracleCamera, PrimaryRaysLandOnTheGroundAtPixelCentres) {
  Scene scene;
  const uint32_t ground = add(scene, grid_mesh(4), trs({0, 0, 0}, 0, {0, 1, 0}, {200, 1, 200}));
  // A quad 0.5 m in front of the eye, nearer than the near plane: clipped away.
  add(scene, z_quad(9.5f, -5, 5, 0, 10), glm::mat4(1.0f));
  Camera cam;
  cam.eye = {0, 5, 10};
  cam.target = {0, 0, 0};
  cam.fov_deg = 50;
  cam.width = 160;
  cam.height = 90;
  cam.near = 1.0f;
  cam.far = 40.0f;
  const CameraHits hits = RayOracle(scene).cast_camera(cam);

  // Reference through GLM's own matrices: the pixel centre's near/far points and y = 0.
  const glm::dmat4 vp =
      glm::perspectiveRH_NO(glm::radians(50.0), 160.0 / 90.0, 1.0, 40.0) *
      glm::lookAtRH(glm::dvec3(cam.eye), glm::dvec3(cam.target), glm::dvec3(0, 1, 0));
  const glm::dmat4 inv = glm::inverse(vp);
  size_t hit_count = 0, miss_count = 0;
  for (uint32_t j = 0; j < cam.height; ++j) {
    for (uint32_t i = 0; i < cam.width; ++i) {
      const size_t k = size_t{j} * cam.width + i;
      const double xn = 2.0 * (i + 0.5) / cam.width - 1.0, yn = 1.0 - 2.0 * (j + 0.5) / cam.height;
      const glm::dvec4 a = inv * glm::dvec4(xn, yn, -1, 1), b = inv * glm::dvec4(xn, yn, 1, 1);
      const glm::dvec3 pa = glm::dvec3(a) / a.w, pb = glm::dvec3(b) / b.w;
      const double s = pa.y / (pa.y - pb.y);  // y = 0 along the near-far segment
      if (s >= 0.0 && s <= 1.0) {
        ++hit_count;
        ASSERT_TRUE(hits.hit(k)) << i << "," << j;
        EXPECT_EQ(hits.instance[k], static_cast<int32_t>(ground));
        const glm::dvec3 expected = pa + s * (pb - pa);
        EXPECT_LT(glm::length(hits.position[k] - expected), 1e-9) << i << "," << j;
        EXPECT_LT(glm::length(hits.normal[k] - glm::dvec3(0, 1, 0)), 1e-12);
      } else {
        ++miss_count;
        EXPECT_FALSE(hits.hit(k)) << i << "," << j;
        EXPECT_TRUE(std::isnan(hits.position[k].x));
      }
    }
  }
  EXPECT_GT(hit_count, 1000u);  // beyond far and above the horizon both occur
  EXPECT_GT(miss_count, 1000u);
}

TEST(OracleMetrics, DepthAndVisibilityCounts) {
  const std::vector<float> e = {0.5f, 1.0f, 0.3f, 0.2f};
  const std::vector<double> r = {0.5, 0.4, 1.0, 0.2 + 5e-6};
  const auto d = compare_depth(e, r, 1e-5);
  EXPECT_EQ(d.agree, 2u);
  EXPECT_EQ(d.oracle_only, 1u);
  EXPECT_EQ(d.engine_only, 1u);
  EXPECT_NEAR(d.max_error, 0.7, 1e-7);
  EXPECT_EQ(d.worst, 2u);

  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto v = compare_visibility(std::vector<float>{1, 0, nan, nan, 0.5f, 1},
                                    std::vector<float>{1, 1, nan, 0, 0.4f, 0});
  EXPECT_EQ(v.both_valid, 4u);
  EXPECT_EQ(v.nan_mismatch, 1u);
  EXPECT_EQ(v.misclassified, 2u);
  EXPECT_EQ(v.penumbra_pixels, 1u);
  EXPECT_NEAR(v.mae, (1 + 0.1 + 1) / 4.0, 1e-6);
}

TEST(OracleMetrics, VisibilityByDistanceSplitsPixelsIntoBands) {
  const float nan = NAN;
  const std::vector<float> engine{1, 0, 1, 0, 1, 1};
  const std::vector<float> reference{1, 1, 1, 0, 0, 1};
  const std::vector<double> distance{1, 5, 20, 60, 700, nan};  // the last pixel sees nothing
  const double edges[] = {10, 50};
  const auto b = compare_visibility_by_distance(engine, reference, distance, edges);
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b[0].label(), "<10 m");
  EXPECT_EQ(b[1].label(), "10-50 m");
  EXPECT_EQ(b[2].label(), ">=50 m");
  EXPECT_EQ(b[0].error.both_valid, 2u);
  EXPECT_EQ(b[0].error.misclassified, 1u);
  EXPECT_EQ(b[1].error.both_valid, 1u);
  EXPECT_EQ(b[1].error.misclassified, 0u);
  EXPECT_EQ(b[2].error.both_valid, 2u);
  EXPECT_NEAR(b[2].error.mae, 0.5, 1e-9);
}

// The estimate's premise, in one dimension: a map of texels [k, k + 1) stores an occluder edge at
// e by its texel centres (k + 0.5 < e: occluded), and a receiver at x is shadowed in truth when
// x < e. Over the edge's phases within a texel, the mean |hard - bilinear| over the receivers is
// the mean share the hard test misclassifies: both a quarter of a texel per edge.
TEST(OracleMetrics, EdgeSamplingEstimateIsTheHardTestsMeanErrorOverEdgePhases) {
  constexpr int kTexels = 16, kPerTexel = 64, kPhases = 97;
  const auto lit = [](int k, double e) { return k + 0.5 >= e ? 1.0f : 0.0f; };
  double estimate = 0, misclassified = 0;
  for (int j = 0; j < kPhases; ++j) {
    const double e = 8.0 + (j + 0.5) / kPhases;
    std::vector<float> hard, bilinear;
    size_t wrong = 0;
    for (int i = 0; i < kTexels * kPerTexel; ++i) {
      const double x = (i + 0.5) / kPerTexel;
      const int k = int(std::floor(x)), left = int(std::floor(x - 0.5));
      const double f = x - 0.5 - left;
      hard.push_back(lit(k, e));
      bilinear.push_back(float((1 - f) * lit(left, e) + f * lit(left + 1, e)));
      wrong += (hard.back() > 0.5f) != (x >= e);
    }
    hard.push_back(NAN), bilinear.push_back(0.5f);  // unseen: not counted
    estimate += edge_sampling_estimate(hard, bilinear);
    misclassified += double(wrong) / (kTexels * kPerTexel);
  }
  // A quarter of a texel of kTexels: 1/64 of the receivers, both ways (exact at these phases).
  EXPECT_NEAR(estimate / kPhases, 0.25 / kTexels, 1e-12);
  EXPECT_NEAR(misclassified / kPhases, 0.25 / kTexels, 1e-12);
  const std::vector<float> a{0, 1}, b{0.5f};
  EXPECT_THROW(edge_sampling_estimate(a, b), std::invalid_argument);
}

}  // namespace
}  // namespace shadow::oracle
