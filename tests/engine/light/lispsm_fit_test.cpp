// The LiSPSM fit as pure math (issue 17): Wimmer's n_opt, and for light directions sweeping
// every case and its boundaries (exactly along the view both ways, 1e-9 off it, grazing, from
// the side) every visible ground receiver and every caster point between it and the light land
// inside the map (w > 0, x, y, z in [0, 1]) on the receiver's texel, no deeper than the
// receiver. No NaN or Inf, also at far/near = 10^6.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/lispsm_fit.hpp"
#include "validation_error.hpp"

namespace shadow {
namespace {

const std::vector<InstanceBounds>& scene() {
  static const std::vector<InstanceBounds> s = {
      {Bounds{{-60, 0, -120}, {60, 0, 20}}, true, true},   // ground
      {Bounds{{-2, 0, -12}, {3, 4, -9}}, true, false},     // block ahead
      {Bounds{{-20, 0, 5}, {20, 15, 6}}, true, false},     // wall behind the camera
      {Bounds{{4, 0.5, -6}, {5, 1.5, -5}}, true, false}};  // small block
  return s;
}

Camera camera(double far_over_near = 4000) {
  Camera cam;
  cam.eye = {0, 2, 0};
  cam.target = {0, 0, -10};
  cam.width = 160, cam.height = 90;
  cam.far = 200.0f;
  cam.near = float(200.0 / far_over_near);
  return cam;
}

glm::dvec3 forward(const Camera& c) {
  return glm::normalize(glm::dvec3(c.target - c.eye));
}

// The light's travel at `angle_deg` from the view direction, turned towards the ground and aside.
Light light_at(const Camera& cam, double angle_deg) {
  const glm::dvec3 f = forward(cam), aside(0.3, -1, 0.1);
  const glm::dvec3 side = glm::normalize(aside - glm::dot(aside, f) * f);
  const double a = glm::radians(angle_deg);
  Light l;
  l.direction = glm::vec3(std::cos(a) * f + std::sin(a) * side);
  return l;
}

glm::dvec3 project(const glm::dmat4& m, const glm::dvec3& p) {
  const glm::dvec4 h = m * glm::dvec4(p, 1.0);
  EXPECT_GT(h.w, 0.0) << p.x << " " << p.y << " " << p.z;
  return glm::dvec3(h) / h.w;
}

// Ground points seen by the camera (a grid of pixel rays hitting y = 0 within far).
std::vector<glm::dvec3> visible_ground(const Camera& cam) {
  std::vector<glm::dvec3> out;
  const glm::dmat4 inv = glm::inverse(
      glm::perspective(glm::radians(double(cam.fov_deg)), double(cam.width) / cam.height,
                       double(cam.near), double(cam.far)) *
      glm::lookAt(glm::dvec3(cam.eye), glm::dvec3(cam.target), glm::dvec3(cam.up)));
  for (int j = 0; j <= 16; ++j)
    for (int i = 0; i <= 16; ++i) {
      const glm::dvec4 a = inv * glm::dvec4(i / 8.0 - 1, j / 8.0 - 1, -1, 1);
      const glm::dvec3 o = glm::dvec3(a) / a.w;
      const glm::dvec3 dir = glm::normalize(o - glm::dvec3(cam.eye));
      if (dir.y > -1e-6) continue;
      const double t = -o.y / dir.y;
      const glm::dvec3 p = o + t * dir;
      if (glm::dot(p - glm::dvec3(cam.eye), forward(cam)) < 0.999 * cam.far && std::abs(p.x) < 60 &&
          p.z > -120)
        out.push_back(p);
    }
  return out;
}

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

// Every receiver lands in the map; the first point of each caster box on the way to the light
// lands on the receiver's texel, no deeper.
void check_covers(const LispsmFit& fit, const Camera& cam, const Light& light, const char* what) {
  SCOPED_TRACE(what);
  ASSERT_TRUE(finite(fit.setup.world_to_ndc)) << fit.light_case;
  const glm::dvec3 d = glm::normalize(glm::dvec3(light.direction));
  const std::vector<glm::dvec3> ground = visible_ground(cam);
  ASSERT_GT(ground.size(), 20u);
  for (const glm::dvec3& p : ground) {
    const glm::dvec3 r = project(fit.setup.world_to_ndc, p);
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(r[k] >= 0.0 && r[k] <= 1.0) << k << " " << r[k];
    for (const InstanceBounds& b : scene()) {
      if (b.receives) continue;
      // Where the ray towards the light enters the box (slab test).
      double lo = 1e-9, hi = INFINITY;
      for (int k = 0; k < 3; ++k) {
        const double dk = -d[k];
        if (std::abs(dk) < 1e-300) {
          if (p[k] < b.world.lo[k] || p[k] > b.world.hi[k]) lo = INFINITY;
          continue;
        }
        const double a = (b.world.lo[k] - p[k]) / dk, c = (b.world.hi[k] - p[k]) / dk;
        lo = std::max(lo, std::min(a, c)), hi = std::min(hi, std::max(a, c));
      }
      if (!(lo < hi)) continue;
      const glm::dvec3 q = project(fit.setup.world_to_ndc, p - hi * d);  // the box's far side
      EXPECT_NEAR(q.x, r.x, 1e-7);
      EXPECT_NEAR(q.y, r.y, 1e-7);
      EXPECT_GE(q.z, 0.0);
      EXPECT_LE(q.z, r.z + 1e-9);
    }
  }
}

TEST(LispsmFit, NOptIsWimmersFormula) {
  const Camera cam = camera();
  const DepthRange measured{5.0, 100.0};
  const double zn = 5.0 * (1 - 1e-3), zf = 100.0 * (1 + 1e-3);
  for (double angle : {90.0, 30.0, 150.0}) {
    const LispsmFit fit = fit_lispsm_light(light_at(cam, angle), cam, scene(), {}, measured);
    // The light's direction is a float vector: its angle is off by ~1e-7 degrees.
    EXPECT_NEAR(fit.gamma_deg, angle, 1e-5);
    const double expected = (zn + std::sqrt(zn * zf)) / std::sin(glm::radians(fit.gamma_deg));
    EXPECT_NEAR(fit.n_opt, expected, 1e-9 * expected) << angle;
    EXPECT_EQ(fit.n, fit.n_opt) << fit.light_case;
  }
  // A requested n is used as given.
  const LispsmFit fit = fit_lispsm_light(light_at(cam, 90), cam, scene(), {7.5}, measured);
  EXPECT_EQ(fit.n, 7.5);
  EXPECT_NE(fit.light_case.find("requested"), std::string::npos) << fit.light_case;
}

// The warp puts more texels near the viewer: along the view, a metre of ground near the eye
// covers more map rows than a metre far away, more so for smaller n; the orthographic map
// (light along the view) covers both alike.
TEST(LispsmFit, WarpShrinksTexelsNearTheViewer) {
  const Camera cam = camera();
  const glm::dvec3 near_p(0, 0, -6), far_p(0, 0, -100), step(0, 0, -1);
  auto ratio = [&](const LispsmFit& fit) {
    const glm::dmat4& m = fit.setup.world_to_ndc;
    const glm::dvec2 a = glm::dvec2(project(m, near_p + step) - project(m, near_p));
    const glm::dvec2 b = glm::dvec2(project(m, far_p + step) - project(m, far_p));
    return glm::length(a) / glm::length(b);
  };
  const Light side = light_at(cam, 90);
  const LispsmFit opt = fit_lispsm_light(side, cam, scene(), {}, DepthRange{2.0, 120.0});
  const LispsmFit strong = fit_lispsm_light(side, cam, scene(), {1.0}, DepthRange{2.0, 120.0});
  const LispsmFit weak = fit_lispsm_light(side, cam, scene(), {1e7}, DepthRange{2.0, 120.0});
  // Measured: n_opt 17.5 -> 27.5x, n 1 -> 346x, n 1e7 (orthographic) -> 1.0x.
  std::printf("[ lispsm   ] near/far texel ratio: n_opt %.3g -> %.3g, n 1 -> %.3g, n 1e7 -> %.3g\n",
              opt.n, ratio(opt), ratio(strong), ratio(weak));
  EXPECT_GT(ratio(opt), 20.0) << opt.light_case;
  EXPECT_GT(ratio(strong), 10 * ratio(opt));
  EXPECT_NEAR(ratio(weak), 1.0, 0.05) << weak.light_case;
  EXPECT_EQ(weak.n, 0.0);  // orthographic: no warp reported
}

TEST(LispsmFit, EveryLightCaseCoversReceiversAndCasters) {
  for (double far_over_near : {4000.0, 1e6}) {
    const Camera cam = camera(far_over_near);
    for (double angle : {0.0, 1e-9, 1.0, 5.0, 30.0, 60.0, 89.99, 90.0, 120.0, 150.0, 175.0, 179.0,
                         180.0 - 1e-9, 180.0}) {
      const Light light = light_at(cam, angle);
      for (const auto& measured :
           {std::optional<DepthRange>{}, std::optional<DepthRange>{DepthRange{2.0, 150.0}}}) {
        const LispsmFit fit = fit_lispsm_light(light, cam, scene(), {}, measured);
        const std::string what = std::to_string(angle) + " deg, far/near " +
                                 std::to_string(far_over_near) + ": " + fit.light_case;
        check_covers(fit, cam, light, what.c_str());
        EXPECT_TRUE(std::isfinite(fit.n)) << what;
        // Exactly along the view there is no direction to warp in: orthographic.
        if (angle == 0.0 || angle == 180.0) {
          EXPECT_EQ(fit.n, 0.0) << what;
        }
        if (angle == 90.0) {
          EXPECT_GT(fit.n, 0.0) << what;
        }
      }
    }
  }
}

// Directional lights only; the warp 0 (n_opt) or within [1e-6, 1e6] x far; no PCSS.
TEST(LispsmFit, ValidationNamesTheField) {
  RenderRequest r = one_triangle_request();
  r.shadow_map.technique = Technique::kLispsm;
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.shadow_map.lispsm.n = 1e-7 * r.camera.far;
  EXPECT_NE(validation_error(r).find("shadow_map.lispsm_n"), std::string::npos);
  r.shadow_map.lispsm.n = NAN;
  EXPECT_NE(validation_error(r).find("shadow_map.lispsm_n"), std::string::npos);
  r.shadow_map.lispsm.n = 2e6 * r.camera.far;
  EXPECT_NE(validation_error(r).find("shadow_map.lispsm_n"), std::string::npos);
  r.shadow_map.lispsm.n = 5;
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.lights[0].type = LightType::kSpot;
  r.lights[0].position = {0, 5, 0};
  EXPECT_NE(validation_error(r).find("shadow_map.technique: TECHNIQUE_LISPSM needs a directional"),
            std::string::npos)
      << validation_error(r);
  r.lights[0].type = LightType::kDirectional;
  r.filter.kind = FilterKind::kPcss;
  r.lights[0].size = 1;
  EXPECT_NE(validation_error(r).find("shadow_map.technique"), std::string::npos);
}

}  // namespace
}  // namespace shadow
