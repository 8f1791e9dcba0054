// The PSM fit as pure math: for light directions sweeping every case and its boundaries (exactly
// along the view both ways, exactly parallel to the image plane and 1e-12 either side), with the
// camera inside the scene's box and a wall behind it, every visible receiver and every caster
// point between it and the light must land inside the map (w > 0, x, y, z in [0, 1]) on the
// receiver's texel, no deeper than the receiver: H = M ∩ S ∩ L is in the map. No NaN or Inf.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <optional>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/psm_fit.hpp"

namespace shadow {
namespace {

InstanceBounds box(glm::dvec3 lo, glm::dvec3 hi, bool receives) {
  return {Bounds{lo, hi}, true, receives};
}

// Where the ray p + t * dir (t > 0) runs inside `b`, if it does.
bool ray_box(const glm::dvec3& p, const glm::dvec3& dir, const Bounds& b, double* t0, double* t1) {
  double lo = 1e-9, hi = INFINITY;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(dir[k]) < 1e-300) {
      if (p[k] < b.lo[k] || p[k] > b.hi[k]) return false;
      continue;
    }
    double a = (b.lo[k] - p[k]) / dir[k], c = (b.hi[k] - p[k]) / dir[k];
    lo = std::max(lo, std::min(a, c)), hi = std::min(hi, std::max(a, c));
  }
  *t0 = lo, *t1 = hi;
  return lo < hi;
}

const std::vector<InstanceBounds>& test_scene() {
  static const std::vector<InstanceBounds> scene = {
      box({-50, 0, -50}, {50, 0, 50}, true),    // ground
      box({-2, 0, -10}, {3, 4, -8}, false),     // block ahead
      box({-20, 0, 5}, {20, 15, 6}, false),     // wall behind the camera
      box({4, 0.5, -6}, {5, 1.5, -5}, false)};  // small block
  return scene;
}

Camera test_camera() {
  Camera cam;
  cam.eye = {0, 2, 0};  // inside the scene's box
  cam.target = {0, 0, -10};
  cam.width = 160, cam.height = 90;
  cam.near = 0.05f, cam.far = 200.0f;
  return cam;
}

// Every visible ground receiver (y = 0) and every caster point between it and the light lands in
// the map, no deeper than the receiver.
PsmFit check_light(const Light& light, const Camera& cam, const std::vector<InstanceBounds>& scene,
                   const PsmSettings& settings, const char* label) {
  const PsmFit fit = fit_psm_light(light, cam, scene, settings);
  const glm::dmat4& m = fit.setup.world_to_ndc;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_TRUE(std::isfinite(m[c][r])) << label;
  const glm::dmat4 cam_m = camera_setup(cam).world_to_ndc;
  const bool directional = light.type == LightType::kDirectional;
  const glm::dvec3 lp(light.position);
  size_t receivers = 0, caster_points = 0;
  double worst_xy = 0, worst_out = 0;
  for (double x = -50; x <= 50; x += 0.5) {
    for (double z = -50; z <= 50; z += 0.5) {
      const glm::dvec3 p(x, 0, z);
      const glm::dvec4 c = cam_m * glm::dvec4(p, 1);
      if (!(c.w > 0 && c.x >= 0 && c.x <= c.w && c.y >= 0 && c.y <= c.w && c.z >= 0 && c.z <= c.w))
        continue;
      ++receivers;
      const glm::dvec4 rp = m * glm::dvec4(p, 1);
      EXPECT_GT(rp.w, 0) << label;
      if (!(rp.w > 0)) return fit;
      const glm::dvec3 to_light =
          directional ? -glm::normalize(glm::dvec3(light.direction)) : glm::normalize(lp - p);
      const double light_t = directional ? INFINITY : glm::length(lp - p);
      const glm::dvec3 rn = glm::dvec3(rp) / rp.w;
      for (int k = 0; k < 3; ++k) worst_out = std::max({worst_out, -rn[k], rn[k] - 1});
      for (size_t i = 1; i < scene.size(); ++i) {
        double t0, t1;
        if (!ray_box(p, to_light, scene[i].world, &t0, &t1)) continue;
        t1 = std::min(t1, light_t);
        if (!(t0 < t1)) continue;
        for (double t : {t0, 0.5 * (t0 + t1), std::min(t1, t0 + 1e3)}) {
          const glm::dvec4 q = m * glm::dvec4(p + t * to_light, 1);
          ++caster_points;
          EXPECT_GT(q.w, 0) << label << " caster " << i;
          if (!(q.w > 0)) return fit;
          const glm::dvec3 qn = glm::dvec3(q) / q.w;
          worst_xy = std::max(worst_xy, glm::length(glm::dvec2(qn - rn)));
          for (int k = 0; k < 3; ++k) worst_out = std::max({worst_out, -qn[k], qn[k] - 1});
          EXPECT_LE(qn.z, rn.z + 1e-9) << label << " caster " << i << " behind its receiver";
        }
      }
    }
  }
  std::printf(
      "[ psm fit  ] %-28s %-60s receivers %zu, caster points %zu, xy drift %.2e, "
      "outside by %.2e\n",
      label, fit.light_case.c_str(), receivers, caster_points, worst_xy, worst_out);
  EXPECT_GT(receivers, 100u);
  EXPECT_LT(worst_out, 1e-9) << label;
  // The orthographic stand-in near the parallel boundary drifts by < 1e-4 of the map.
  EXPECT_LT(worst_xy, 1e-4) << label;
  return fit;
}

void check(const glm::dvec3& travel, PsmCasters casters, const char* label,
           PsmNear near = PsmNear::kReceivers) {
  Light light;
  light.direction = glm::vec3(travel);
  PsmSettings settings;
  settings.casters = casters;
  settings.near = near;
  check_light(light, test_camera(), test_scene(), settings, label);
}

TEST(PsmFit, EveryDirectionalCaseKeepsReceiversAndCastersInTheMap) {
  const glm::dvec3 f = glm::normalize(glm::dvec3(0, -2, -10));
  const glm::dvec3 side = glm::normalize(glm::cross(f, glm::dvec3(1, 0, 0)));  // perpendicular
  const glm::dvec3 down = side.y < 0 ? side : -side;
  struct Dir {
    const char* name;
    glm::dvec3 d;
  };
  const Dir dirs[] = {
      {"along view", f},
      {"against view", -f},
      {"perpendicular", down},
      {"perpendicular +1e-12", glm::normalize(down + 1e-12 * f)},
      {"perpendicular -1e-12", glm::normalize(down - 1e-12 * f)},
      {"behind 1 deg", glm::normalize(std::cos(0.01745) * f + std::sin(0.01745) * down)},
      {"behind 60 deg", glm::normalize(0.5 * f + 0.866 * down)},
      {"front 5 deg", glm::normalize(-std::cos(0.0873) * f + std::sin(0.0873) * down)},
      {"front 60 deg", glm::normalize(-0.5 * f + 0.866 * down)},
      {"grazing behind 89.9 deg", glm::normalize(0.001745 * f + down)},
      {"straight down", {0, -1, 0}},
  };
  for (const Dir& d : dirs) {
    check(d.d, PsmCasters::kInverseProjection, d.name);
    check(d.d, PsmCasters::kSlideBack, (std::string(d.name) + " slide").c_str());
    check(d.d, PsmCasters::kInverseProjection, (std::string(d.name) + " virtual").c_str(),
          PsmNear::kVirtualSlideBack);
  }
}

// The near-plane quad of a fit's virtual camera: its view's inverse applied to the corners at
// depth virtual_near, half-height virtual_near * tan(fovy / 2).
std::array<glm::dvec3, 4> near_quad(const PsmFit& fit, double aspect) {
  const glm::dmat4 to_world = glm::inverse(fit.setup.view);
  const double h = fit.virtual_near * std::tan(0.5 * glm::radians(fit.virtual_fovy_deg));
  std::array<glm::dvec3, 4> q;
  int i = 0;
  for (double sx : {-1.0, 1.0})
    for (double sy : {-1.0, 1.0})
      q[i++] = glm::dvec3(to_world * glm::dvec4(sx * h * aspect, sy * h, -fit.virtual_near, 1));
  return q;
}

// Kozlov 14.1.2, Fig 14-6: the virtual slide-back moves the camera back and the near plane
// forward by the same distance, with a narrower field of view: the near-plane quad is the same.
TEST(PsmFit, VirtualSlideBackKeepsTheNearPlaneQuad) {
  Camera cam;
  cam.eye = {3, 2, 7};
  cam.target = {0, 0, -10};
  cam.width = 160, cam.height = 90;
  cam.near = 0.05f, cam.far = 200.0f;
  const std::vector<InstanceBounds> scene = {box({-50, 0, -50}, {50, 0, 50}, true),
                                             box({-2, 0, -10}, {3, 4, -8}, false)};
  Light light;
  light.direction = glm::normalize(glm::vec3(0.2f, -1.0f, -0.4f));
  const double aspect = 160.0 / 90.0;
  double worst = 0;
  for (const std::optional<DepthRange>& measured :
       {std::optional<DepthRange>{}, std::optional<DepthRange>{DepthRange{4.5, 60.0}}}) {
    for (double slide : {0.0, 0.3, 25.0, 1e4}) {
      PsmSettings pushed;
      const PsmFit a = fit_psm_light(light, cam, scene, pushed, measured);
      PsmSettings virt = pushed;
      virt.near = PsmNear::kVirtualSlideBack;
      virt.virtual_slide = slide;
      const PsmFit b = fit_psm_light(light, cam, scene, virt, measured);
      const double expect_slide = slide > 0 ? slide : a.virtual_near;  // default: near doubles
      EXPECT_NEAR(b.virtual_slide, expect_slide, 1e-12 * expect_slide);
      EXPECT_NEAR(b.slide_back, expect_slide, 1e-12 * expect_slide);
      EXPECT_NEAR(b.virtual_near, a.virtual_near + expect_slide, 1e-9 * b.virtual_near);
      EXPECT_NEAR(b.virtual_far, a.virtual_far + expect_slide, 1e-9 * b.virtual_far);
      EXPECT_LT(b.virtual_fovy_deg, a.virtual_fovy_deg);
      const auto qa = near_quad(a, aspect), qb = near_quad(b, aspect);
      for (int i = 0; i < 4; ++i)
        worst = std::max(worst, glm::length(qa[i] - qb[i]) / glm::length(qa[i]));
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) ASSERT_TRUE(std::isfinite(b.setup.world_to_ndc[c][r]));
      std::printf("[ psm fit  ] virtual slide %g: near %.6g -> %.6g, fovy %.6g -> %.6g deg, %s\n",
                  slide, a.virtual_near, b.virtual_near, a.virtual_fovy_deg, b.virtual_fovy_deg,
                  b.light_case.c_str());
    }
  }
  std::printf("[ psm fit  ] near-plane quad moved by %.3g (relative)\n", worst);
  EXPECT_LT(worst, 1e-9);
}

// The point-light cases, as pure math (the engine still rejects point lights with PSM;
// spot lights share this path): a horizontal camera at height 2 looking along -z, so its camera
// plane is z = 0 exactly in float. In the camera plane, 1e-6 (relative) in front of and behind
// it, and inside the view frustum (between the camera and a wall of receivers: a point light;
// among the receivers: no single frustum, needs_cube).
TEST(PsmFit, PointLightCases) {
  Camera cam = test_camera();
  cam.target = {0, 2, -10};
  Light light;
  light.type = LightType::kPoint;
  struct PointCase {
    const char* name;
    glm::vec3 position;
    const char* light_case;  // start of the expected case
  };
  const PointCase cases[] = {
      {"camera plane", {8, 6, 0}, "point in the camera plane: directional"},
      {"just in front", {8, 6, -1e-5f}, "point from the front: point light"},
      {"just behind", {8, 6, 1e-5f}, "point from behind: inverted point light"},
      {"behind", {3, 9, 4}, "point from behind: inverted point light"},
  };
  for (const PointCase& c : cases) {
    light.position = c.position;
    const PsmFit fit = check_light(light, cam, test_scene(), PsmSettings{}, c.name);
    EXPECT_EQ(fit.light_case.rfind(c.light_case, 0), 0u) << c.name << ": " << fit.light_case;
    EXPECT_FALSE(fit.needs_cube) << c.name;
  }
  // Inside the view frustum, in front of a wall of receivers 50 m ahead (ground not receiving).
  const std::vector<InstanceBounds> wall = {box({-60, -40, -51}, {60, 40, -50}, true),
                                            box({-50, 0, -50}, {50, 0, 50}, false),
                                            box({-1, 1, -30}, {1, 3, -28}, false)};
  light.position = {0, 2.5f, -10};
  PsmFit fit = fit_psm_light(light, cam, wall, PsmSettings{});
  std::printf("[ psm fit  ] point in view before a wall: %s\n", fit.light_case.c_str());
  EXPECT_EQ(fit.light_case.rfind("point from the front: point light", 0), 0u) << fit.light_case;
  EXPECT_FALSE(fit.needs_cube);
  // Every visible point of the wall (z = -50) maps inside the map, depth in [0, 1].
  const glm::dmat4 cam_m = camera_setup(cam).world_to_ndc;
  size_t inside = 0;
  double worst_out = 0;
  for (double x = -60; x <= 60; x += 0.5)
    for (double y = -40; y <= 40; y += 0.5) {
      const glm::dvec4 cp = cam_m * glm::dvec4(x, y, -50, 1);
      if (!(cp.w > 0 && cp.x >= 0 && cp.x <= cp.w && cp.y >= 0 && cp.y <= cp.w)) continue;
      ++inside;
      const glm::dvec4 q = fit.setup.world_to_ndc * glm::dvec4(x, y, -50, 1);
      ASSERT_GT(q.w, 0);
      for (int k = 0; k < 3; ++k) worst_out = std::max({worst_out, -q[k] / q.w, q[k] / q.w - 1});
      // The block between the light and the wall shadows it: its centre lands on the texel of
      // the wall point behind it, nearer to the light.
    }
  EXPECT_GT(inside, 1000u);
  EXPECT_LT(worst_out, 1e-9);
  const glm::dvec3 block(0, 2, -29),
      behind = glm::dvec3(light.position) + (block - glm::dvec3(light.position)) * (40.0 / 19.0);
  const glm::dvec4 qb = fit.setup.world_to_ndc * glm::dvec4(block, 1),
                   qw = fit.setup.world_to_ndc * glm::dvec4(behind, 1);
  EXPECT_NEAR(qb.x / qb.w, qw.x / qw.w, 1e-9);
  EXPECT_NEAR(qb.y / qb.w, qw.y / qw.w, 1e-9);
  EXPECT_LT(qb.z / qb.w, qw.z / qw.w);
  // Among the receivers (above the ground, inside its post-perspective box): cube faces.
  light.position = {0, 1, -10};
  fit = fit_psm_light(light, cam, test_scene(), PsmSettings{});
  std::printf("[ psm fit  ] point among the receivers: %s\n", fit.light_case.c_str());
  EXPECT_TRUE(fit.needs_cube);
  EXPECT_NE(fit.light_case.find("needs a cube map"), std::string::npos);
  // A spot light there falls back to the uniform spot map.
  light.type = LightType::kSpot;
  light.direction = {0, -1, 0};
  light.cone_angle_deg = 120;
  fit = fit_psm_light(light, cam, test_scene(), PsmSettings{});
  EXPECT_TRUE(fit.needs_cube);
  EXPECT_EQ(fit.light_case.rfind("spot from the front", 0), 0u) << fit.light_case;
  EXPECT_NE(fit.light_case.find(": uniform"), std::string::npos) << fit.light_case;
  EXPECT_EQ(fit.setup.world_to_ndc, fit_uniform_light(light, cam, test_scene()).world_to_ndc);
}

// PSM_CUBE's faces for a table of light positions (the post-perspective light in front of,
// behind, above, beside and inside the unit cube): a side is used when it faces away from the
// light (3 to 5 outside the cube, 6 inside), rendered when visible receivers lie behind it, and
// every visible receiver's box corner inside the view lies in exactly its own face's map.
TEST(PsmFit, PsmCubeFacesForATableOfLightPositions) {
  const Camera cam = test_camera();
  const glm::dvec3 eye(cam.eye), fwd = glm::normalize(glm::dvec3(cam.target) - eye);
  const glm::dvec3 right = glm::normalize(glm::cross(fwd, glm::dvec3(cam.up)));
  const glm::dvec3 up = glm::cross(right, fwd);
  auto directional = [](glm::dvec3 travel) {
    Light l;
    l.direction = glm::vec3(glm::normalize(travel));
    return l;
  };
  auto point = [&](glm::dvec3 offset) {  // from the eye along right, up, forward
    Light l;
    l.type = LightType::kPoint;
    l.position = glm::vec3(eye + offset.x * right + offset.y * up + offset.z * fwd);
    return l;
  };
  struct Row {
    const char* name;
    Light light;
    int sides;  // used
  };
  const std::vector<Row> rows = {
      {"facing the camera (in front, beyond z = 1)", directional(-fwd + 0.05 * up), 5},
      {"from behind (inverted, beyond z = 1)", directional(fwd - 0.3 * up), 5},
      {"above the view and in front", point({0, 40, 20}), 5},
      {"beside and above the view", point({60, 40, 20}), 4},
      {"beside, above and beyond the far plane", point({1000, 600, 400}), 3},
      {"inside the view frustum", point({0, -1, 6}), 6}};
  for (const Row& row : rows) {
    const PsmCubeFit fit =
        fit_psm_cube(row.light, cam, test_scene(), PsmSettings{}, std::nullopt, 1024, 1);
    ASSERT_TRUE(fit.cube) << row.name << ": " << fit.fit.light_case;
    int used = 0, rendered = 0;
    for (const CubeFaceFit& f : fit.faces) {
      used += f.reason != "faces the light";
      rendered += f.rendered;
      for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 4; ++k) EXPECT_TRUE(std::isfinite(f.setup.world_to_ndc[c][k]));
    }
    std::printf("[ psm cube ] %s: %d sides used, %d rendered; %s\n", row.name, used, rendered,
                fit.fit.light_case.c_str());
    EXPECT_EQ(used, row.sides) << row.name;
    EXPECT_GE(rendered, 1) << row.name;
    EXPECT_GT(fit.texel_min, 0.0);
    EXPECT_LE(fit.texel_max, 1.0 / 1024 * 1.01);  // never coarser than a whole side per map
    // Visible ground points: each inside its own face's map, at depth in [0, 1].
    const glm::dmat4 cam_tex = camera_setup(cam).world_to_ndc, inv = glm::inverse(cam_tex);
    int checked = 0;
    for (double u : {0.1, 0.5, 0.9})
      for (double v : {0.6, 0.8, 0.95}) {
        const glm::dvec4 a = inv * glm::dvec4(u, v, 0, 1), b = inv * glm::dvec4(u, v, 1, 1);
        const glm::dvec3 pa = glm::dvec3(a) / a.w, pb = glm::dvec3(b) / b.w;
        if (!(pa.y > 0 && pb.y < 0)) continue;  // the ray misses the ground
        const glm::dvec3 x = pa + (pb - pa) * (pa.y / (pa.y - pb.y));
        const int k = face_of(fit.faces[0].setup.faces, x);
        ++checked;
        ASSERT_TRUE(fit.faces[k].rendered) << row.name << " face " << k;
        const glm::dvec4 c = fit.faces[k].setup.world_to_ndc * glm::dvec4(x, 1.0);
        const glm::dvec3 ndc = glm::dvec3(c) / c.w;
        EXPECT_GT(c.w, 0.0) << row.name;
        for (int i = 0; i < 3; ++i) {
          EXPECT_GE(ndc[i], -1e-9) << row.name << " face " << k << " axis " << i;
          EXPECT_LE(ndc[i], 1 + 1e-9) << row.name << " face " << k << " axis " << i;
        }
      }
    EXPECT_EQ(checked, 9) << row.name;
  }
}

// A point light inside a room that is one caster box (its surface far from the light) with a
// table between the light and the floor: no face's near plane may clip the table (a box around
// the light may hold geometry anywhere near it).
TEST(PsmFit, PsmCubeKeepsCastersInsideABoxAroundTheLight) {
  Camera cam = test_camera();
  const std::vector<InstanceBounds> room = {box({-30, 0, -40}, {30, 20, 10}, true)};
  Light lamp;
  lamp.type = LightType::kPoint;
  lamp.position = {0.5f, 1.6f, -6.0f};  // in view, inside the room
  const PsmCubeFit fit = fit_psm_cube(lamp, cam, room, PsmSettings{}, std::nullopt, 1024, 1);
  ASSERT_TRUE(fit.cube) << fit.fit.light_case;
  // Points of a table top 0.3 m under the lamp, and of the floor below it.
  for (const glm::dvec3 x :
       {glm::dvec3(0.3, 1.3, -6.1), glm::dvec3(0.7, 1.3, -5.8), glm::dvec3(0.5, 0.0, -6.0)}) {
    const int k = face_of(fit.faces[0].setup.faces, x);
    ASSERT_TRUE(fit.faces[k].rendered) << k;
    const glm::dvec4 c = fit.faces[k].setup.world_to_ndc * glm::dvec4(x, 1.0);
    EXPECT_GT(c.w, 0.0);
    EXPECT_GE(c.z / c.w, 0.0) << "clipped by face " << k << "'s near plane";
    EXPECT_LE(c.z / c.w, 1.0);
  }
}

}  // namespace
}  // namespace shadow
