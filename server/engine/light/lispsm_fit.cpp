#include "engine/light/lispsm_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/geometry.hpp"

namespace shadow {
namespace {

glm::dmat4 from_rows(const glm::dvec4& x, const glm::dvec4& y, const glm::dvec4& z,
                     const glm::dvec4& w) {
  return glm::transpose(glm::dmat4(x, y, z, w));
}

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

// The warp fades into the orthographic map when n is this many receiver y-extents: texel sizes
// then change by < 1e-4 across the map (as PSM's nearly-parallel light, psm_fit.cpp).
constexpr double kOrthographicRatio = 1e4;

}  // namespace

LispsmFit fit_lispsm_light(const Light& light, const Camera& camera,
                           const std::vector<InstanceBounds>& instances,
                           const LispsmSettings& settings,
                           const std::optional<DepthRange>& measured) {
  LispsmFit fit;
  const glm::dvec3 eye(camera.eye), fwd = glm::normalize(glm::dvec3(camera.target) - eye);
  const glm::dmat4 view = glm::lookAt(eye, eye + fwd, glm::dvec3(camera.up));
  const glm::dmat4 clip_cam = glm::perspective(glm::radians(double(camera.fov_deg)),
                                               double(camera.width) / double(camera.height),
                                               double(camera.near), double(camera.far)) *
                              view;
  const std::vector<glm::dvec3> receivers = visible_receiver_points(clip_cam, instances);
  if (receivers.empty()) {
    fit.setup = fit_uniform_light(light, camera, instances);
    fit.light_case = "lispsm: no visible receiver: uniform: directional";
    return fit;
  }

  // Light space: z towards the light, y along the view direction projected across the light.
  const glm::dvec3 d = glm::normalize(glm::dvec3(light.direction));
  const double cos_g = glm::dot(fwd, d), sin_g = glm::length(glm::cross(fwd, d));
  fit.gamma_deg = glm::degrees(std::atan2(sin_g, cos_g));
  glm::dvec3 up = fwd - cos_g * d;
  if (glm::length(up) > 1e-12)
    up = glm::normalize(up);
  else  // the light exactly along the view: no direction to warp in
    up = std::abs(d.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
  Bounds world_box;
  for (const glm::dvec3& p : receivers) world_box.extend(p);
  const glm::dvec3 c = 0.5 * (world_box.lo + world_box.hi);
  const glm::dmat4 lview = glm::lookAt(c - d, c, up);
  fit.setup.view = lview;

  std::vector<glm::dvec3> rl;  // receivers in light view
  Bounds lr;
  for (const glm::dvec3& p : receivers) {
    rl.push_back(glm::dvec3(lview * glm::dvec4(p, 1.0)));
    lr.extend(rl.back());
  }
  // A little slack so that surfaces on the fitted planes are not clipped by rounding.
  const glm::dvec3 pad = 1e-3 * (lr.hi - lr.lo) + 1e-6 * std::max(1.0, glm::length(c));
  const double x0 = lr.lo.x - pad.x, x1 = lr.hi.x + pad.x;
  const double y0 = lr.lo.y - pad.y, y1 = lr.hi.y + pad.y, dy = y1 - y0;
  const double tmax = -lr.lo.z + pad.z;  // t = depth along the light's travel = -z

  // The warp's n: Wimmer's n_opt from the receivers' view-depth range, or the request's.
  double zn = INFINITY, zf = -INFINITY;
  for (const glm::dvec3& p : receivers) {
    const double z = glm::dot(p - eye, fwd);
    zn = std::min(zn, z), zf = std::max(zf, z);
  }
  if (measured && std::isfinite(measured->min) && std::isfinite(measured->max) &&
      measured->min <= measured->max)
    zn = measured->min * (1 - 1e-3), zf = measured->max * (1 + 1e-3);
  zn = std::max(zn, double(camera.near));
  zf = std::max(zf, 1.001 * zn);
  fit.n_opt = sin_g > 0 ? (zn + std::sqrt(zn * zf)) / sin_g : INFINITY;
  const bool requested = settings.n > 0;
  const double n = requested ? settings.n : fit.n_opt;
  const bool ortho = !(n <= kOrthographicRatio * dy);
  const double yc = y0 - n;  // the warp's centre (and x at the eye's)
  const double xc = glm::dvec3(lview * glm::dvec4(eye, 1.0)).x;

  // Casters that can shadow a receiver lie over the receivers' x/y extent, on the light's side
  // of the farthest receiver: their box surfaces clipped to that prism.
  const std::vector<glm::dvec4> prism = {
      to_world(lview, {1, 0, 0, -x0}), to_world(lview, {-1, 0, 0, x1}),
      to_world(lview, {0, 1, 0, -y0}), to_world(lview, {0, -1, 0, y1}),
      to_world(lview, {0, 0, 1, tmax})};
  std::vector<glm::dvec3> depth_points = rl;
  for (const InstanceBounds& ib : instances)
    if (ib.casts)
      for_each_clipped_vertex(ib.world, prism, [&](const glm::dvec4& v) {
        depth_points.push_back(glm::dvec3(lview * (v / v.w)));
      });
  double tmin = INFINITY;
  for (const glm::dvec3& q : depth_points) tmin = std::min(tmin, -q.z);
  tmin -= 1e-3 * (tmax - tmin) + 1e-6;

  glm::dmat4 t;
  char what[160];
  if (ortho) {
    t = from_rows({1 / (x1 - x0), 0, 0, -x0 / (x1 - x0)}, {0, 1 / dy, 0, -y0 / dy},
                  {0, 0, -1 / (tmax - tmin), -tmin / (tmax - tmin)}, {0, 0, 0, 1});
    std::snprintf(what, sizeof what,
                  "lispsm: light along the view (gamma %.2f deg, n %.6g%s): "
                  "orthographic",
                  fit.gamma_deg, n, requested ? " requested" : " n_opt");
  } else {
    // u = (x - xc)/s over the receivers; depth (t - tmin)/s over receivers and casters.
    double u0 = INFINITY, u1 = -INFINITY, zhi = 0;
    for (const glm::dvec3& q : rl) {
      const double u = (q.x - xc) / (q.y - yc);
      u0 = std::min(u0, u), u1 = std::max(u1, u);
    }
    for (const glm::dvec3& q : depth_points) zhi = std::max(zhi, (-q.z - tmin) / (q.y - yc));
    const double pu = 1e-3 * (u1 - u0) + 1e-12;
    u0 -= pu, u1 += pu, zhi *= 1.001;
    // Homogeneous rows over light-view (x, y, z, 1): w = s = y - yc; v = the warp's depth,
    // 0 at y0 and 1 at y1: (n + dy)/dy * (y - y0)/s.
    const double ku = 1 / (u1 - u0), kv = (n + dy) / dy;
    t = from_rows({ku, -ku * u0, 0, ku * (u0 * yc - xc)}, {0, kv, 0, -kv * y0},
                  {0, 0, -1 / zhi, -tmin / zhi}, {0, 1, 0, -yc});
    fit.n = n;
    std::snprintf(what, sizeof what, "lispsm: n %.6g (%s), n_opt %.6g, gamma %.2f deg", n,
                  requested ? "requested" : "n_opt", fit.n_opt, fit.gamma_deg);
  }
  fit.light_case = what;
  fit.setup.world_to_ndc = t * lview;
  if (!finite(fit.setup.world_to_ndc)) {
    fit.setup = fit_uniform_light(light, camera, instances);
    fit.n = 0;
    fit.light_case += ", degenerate fit: uniform: directional";
  }
  return fit;
}

}  // namespace shadow
