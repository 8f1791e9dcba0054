#include "engine/light_space.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace shadow {

std::array<glm::dvec3, 8> Bounds::corners() const {
  std::array<glm::dvec3, 8> c;
  for (int i = 0; i < 8; ++i)
    c[i] = {(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
  return c;
}

Bounds transform_bounds(const Bounds& b, const glm::dmat4& m) {
  Bounds out;
  if (b.empty()) return out;
  for (const glm::dvec3& p : b.corners()) {
    glm::dvec4 q = m * glm::dvec4(p, 1.0);
    out.extend(glm::dvec3(q) / q.w);
  }
  return out;
}

Bounds intersect(const Bounds& a, const Bounds& b) {
  Bounds out{glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)};
  return out.empty() ? Bounds{} : out;
}

glm::dmat4 gl_to_texture_ndc() {
  // x' = (x + 1) / 2, y' = (1 - y) / 2, z' = (z + 1) / 2 (columns below).
  return glm::dmat4(0.5, 0.0, 0.0, 0.0,   //
                    0.0, -0.5, 0.0, 0.0,  //
                    0.0, 0.0, 0.5, 0.0,   //
                    0.5, 0.5, 0.5, 1.0);
}

namespace {

// An up vector that is not parallel to `forward`.
glm::dvec3 any_up(const glm::dvec3& forward) {
  glm::dvec3 a = glm::abs(forward);
  return (a.y < 0.9) ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
}

// The camera frustum's corners in world space.
Bounds frustum_box(const glm::dmat4& world_to_ndc) {
  return transform_bounds(Bounds{glm::dvec3(0.0), glm::dvec3(1.0)}, glm::inverse(world_to_ndc));
}

// Where the visible receivers can be: each visible receiver's box clipped to the frustum's box.
// Falls back to every receiver (then every instance) so the map is never degenerate.
Bounds receiver_region(const Camera& camera, const std::vector<InstanceBounds>& instances) {
  ViewSetup cam = camera_setup(camera);
  Bounds frustum = frustum_box(cam.world_to_ndc);
  Bounds visible, all_receivers, everything;
  for (const InstanceBounds& ib : instances) {
    everything.extend(ib.world);
    if (!ib.receives) continue;
    all_receivers.extend(ib.world);
    if (may_be_visible(ib.world, cam.world_to_ndc)) visible.extend(intersect(ib.world, frustum));
  }
  if (!visible.empty()) return visible;
  if (!all_receivers.empty()) return all_receivers;
  if (!everything.empty()) return everything;
  return Bounds{glm::dvec3(-1.0), glm::dvec3(1.0)};
}

bool overlaps_xy(const Bounds& a, const Bounds& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y;
}

// In light space a shadow lies straight down the light's z from its caster, so the map needs
// only the part of the visible receivers' extent that some caster's extent overlaps; receivers
// outside the map are lit. Depth still spans every such receiver, so none falls past far.
ViewSetup fit_directional(const Light& light, const Bounds& receivers,
                          const std::vector<InstanceBounds>& instances) {
  glm::dvec3 d = glm::normalize(glm::dvec3(light.direction));
  glm::dvec3 c = 0.5 * (receivers.lo + receivers.hi);
  ViewSetup s;
  s.view = glm::lookAt(c - d, c, any_up(d));
  Bounds r = transform_bounds(receivers, s.view);
  double near = -r.hi.z, far = -r.lo.z;  // depths along the light's travel
  Bounds casters;
  for (const InstanceBounds& ib : instances) {
    if (!ib.casts) continue;
    Bounds lb = transform_bounds(ib.world, s.view);
    if (lb.empty() || !overlaps_xy(lb, r) || -lb.hi.z > far) continue;
    near = std::min(near, -lb.hi.z);
    casters.extend(lb);
  }
  glm::dvec2 lo(r.lo), hi(r.hi);
  if (!casters.empty()) {
    lo = glm::max(lo, glm::dvec2(casters.lo));
    hi = glm::min(hi, glm::dvec2(casters.hi));
  }
  // A little slack so that surfaces on the fitted planes are not clipped by rounding.
  double pad_z = 1e-3 * (far - near) + 1e-6 * std::max({1.0, std::abs(near), std::abs(far)});
  glm::dvec2 pad = 1e-3 * (hi - lo) + 1e-6;
  glm::dmat4 proj =
      glm::ortho(lo.x - pad.x, hi.x + pad.x, lo.y - pad.y, hi.y + pad.y, near - pad_z, far + pad_z);
  s.world_to_ndc = gl_to_texture_ndc() * proj * s.view;
  return s;
}

ViewSetup fit_spot(const Light& light, const Bounds& receivers,
                   const std::vector<InstanceBounds>& instances) {
  glm::dvec3 p(light.position), axis = glm::normalize(glm::dvec3(light.direction));
  ViewSetup s;
  s.view = glm::lookAt(p, p + axis, any_up(axis));
  // Depths of box corners in front of the light (the view looks down -z).
  auto depth_range = [&](const Bounds& b, double& lo, double& hi) {
    for (const glm::dvec3& q : b.corners()) {
      double depth = -(s.view * glm::dvec4(q, 1.0)).z;
      lo = std::min(lo, depth);
      hi = std::max(hi, depth);
    }
  };
  double r_lo = INFINITY, far = -INFINITY;
  depth_range(receivers, r_lo, far);
  far = std::max(far, 1e-6);
  double near = r_lo;
  for (const InstanceBounds& ib : instances) {
    if (!ib.casts || ib.world.empty()) continue;
    double lo = INFINITY, hi = -INFINITY;
    depth_range(ib.world, lo, hi);
    if (hi > 0.0) near = std::min(near, lo);
  }
  // A caster around the light itself would put near at or behind it: keep 1e-4 of the range.
  near = std::clamp(near * 0.999, far * 1e-4, far);
  far *= 1.001;
  glm::dmat4 proj = glm::perspective(glm::radians(double(light.cone_angle_deg)), 1.0, near, far);
  s.world_to_ndc = gl_to_texture_ndc() * proj * s.view;
  return s;
}

}  // namespace

ViewSetup camera_setup(const Camera& camera) {
  ViewSetup s;
  s.view = glm::lookAt(glm::dvec3(camera.eye), glm::dvec3(camera.target), glm::dvec3(camera.up));
  glm::dmat4 proj = glm::perspective(glm::radians(double(camera.fov_deg)),
                                     double(camera.width) / double(camera.height),
                                     double(camera.near), double(camera.far));
  s.world_to_ndc = gl_to_texture_ndc() * proj * s.view;
  return s;
}

bool may_be_visible(const Bounds& b, const glm::dmat4& world_to_ndc) {
  if (b.empty()) return false;
  int outside[6] = {0, 0, 0, 0, 0, 0};
  for (const glm::dvec3& p : b.corners()) {
    glm::dvec4 c = world_to_ndc * glm::dvec4(p, 1.0);
    outside[0] += c.x < 0.0;
    outside[1] += c.x > c.w;
    outside[2] += c.y < 0.0;
    outside[3] += c.y > c.w;
    outside[4] += c.z < 0.0;
    outside[5] += c.z > c.w;
  }
  return std::none_of(outside, outside + 6, [](int n) { return n == 8; });
}

ViewSetup fit_uniform_light(const Light& light, const Camera& camera,
                            const std::vector<InstanceBounds>& instances) {
  Bounds receivers = receiver_region(camera, instances);
  return light.type == LightType::kSpot ? fit_spot(light, receivers, instances)
                                        : fit_directional(light, receivers, instances);
}

}  // namespace shadow
