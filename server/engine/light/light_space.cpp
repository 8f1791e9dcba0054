#include "engine/light/light_space.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "wire/errors.hpp"

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
// The receivers a map covers: those the camera sees (kView), or all of them (kScene).
Bounds receiver_region(const Camera& camera, const std::vector<InstanceBounds>& instances,
                       MapFit fit) {
  ViewSetup cam = camera_setup(camera);
  Bounds frustum = frustum_box(cam.world_to_ndc);
  Bounds visible, all_receivers, everything;
  for (const InstanceBounds& ib : instances) {
    everything.extend(ib.world);
    if (!ib.receives) continue;
    all_receivers.extend(ib.world);
    if (fit == MapFit::kView && may_be_visible(ib.world, cam.world_to_ndc))
      visible.extend(intersect(ib.world, frustum));
  }
  if (!visible.empty()) return visible;
  if (!all_receivers.empty()) return all_receivers;
  if (!everything.empty()) return everything;
  return Bounds{glm::dvec3(-1.0), glm::dvec3(1.0)};
}

bool overlaps_xy(const Bounds& a, const Bounds& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y;
}

// A caster far up the light's path (a stray vertex at 1e38, say) stretches the map's depth range
// until float32 depth no longer separates the casters near the receivers from those receivers,
// and every shadow is lost. Refused when one depth step (2^-24 of the range) is coarser than
// 1/4096 of the map's width, i.e. than a texel of the largest map.
constexpr size_t kNoInstance = ~size_t{0};

void check_depth_resolution(double depth_range, double width, size_t nearest) {
  const double step = std::ldexp(depth_range, -24);
  if (!(step > width / 4096.0)) return;
  char text[320];
  std::snprintf(text, sizeof text,
                "reaches %.3g world units up the light's path from the receivers in view, so "
                "the shadow map's float32 depth would resolve only %.3g units while its width is "
                "%.3g: every shadow would be lost; remove or fix the far-away geometry",
                depth_range, step, width);
  throw InvalidArgument(
      nearest == kNoInstance ? "scene" : "scene.instances[" + std::to_string(nearest) + "]", text);
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
  size_t nearest = kNoInstance;  // the caster that sets the near plane
  for (size_t i = 0; i < instances.size(); ++i) {
    const InstanceBounds& ib = instances[i];
    if (!ib.casts) continue;
    Bounds lb = transform_bounds(ib.world, s.view);
    if (lb.empty() || !overlaps_xy(lb, r) || -lb.hi.z > far) continue;
    if (-lb.hi.z < near) near = -lb.hi.z, nearest = i;
    casters.extend(lb);
  }
  glm::dvec2 lo(r.lo), hi(r.hi);
  if (!casters.empty()) {
    lo = glm::max(lo, glm::dvec2(casters.lo));
    hi = glm::min(hi, glm::dvec2(casters.hi));
  }
  check_depth_resolution(far - near, std::min(hi.x - lo.x, hi.y - lo.y), nearest);
  // A little slack so that surfaces on the fitted planes are not clipped by rounding.
  double pad_z = 1e-3 * (far - near) + 1e-6 * std::max({1.0, std::abs(near), std::abs(far)});
  glm::dvec2 pad = 1e-3 * (hi - lo) + 1e-6;
  glm::dmat4 proj =
      glm::ortho(lo.x - pad.x, hi.x + pad.x, lo.y - pad.y, hi.y + pad.y, near - pad_z, far + pad_z);
  s.world_to_ndc = gl_to_texture_ndc() * proj * s.view;
  s.depth = {MapDepth::kOrthographic, near - pad_z, far + pad_z};
  return s;
}

// The depth range, along the view's -z, of the part of `box` inside the square pyramid
// |x|, |y| <= tan_half * depth of `view`; empty (lo > hi) when none of it is. The part's
// vertices lie on the box's faces clipped to the pyramid, or at the apex if the box holds it.
struct DepthRange {
  double lo = INFINITY, hi = -INFINITY;
  bool empty() const { return lo > hi; }
};

DepthRange depth_in_pyramid(const Bounds& box, const glm::dmat4& view, double tan_half) {
  DepthRange r;
  if (box.empty()) return r;
  const std::array<glm::dvec3, 8> c = box.corners();
  std::array<glm::dvec3, 8> v;
  for (int i = 0; i < 8; ++i) v[i] = glm::dvec3(view * glm::dvec4(c[i], 1.0));
  auto inside = [&](const glm::dvec3& p, int plane) {
    const double d = -p.z * tan_half;
    return plane == 0 ? d - p.x : plane == 1 ? d + p.x : plane == 2 ? d - p.y : d + p.y;
  };
  // Corner indices of the six faces (bit 0 = x, bit 1 = y, bit 2 = z).
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  for (const auto& face : kFaces) {
    std::vector<glm::dvec3> poly = {v[face[0]], v[face[1]], v[face[2]], v[face[3]]};
    for (int plane = 0; plane < 4 && !poly.empty(); ++plane) {
      std::vector<glm::dvec3> out;
      for (size_t k = 0; k < poly.size(); ++k) {
        const glm::dvec3 &a = poly[k], &b = poly[(k + 1) % poly.size()];
        const double da = inside(a, plane), db = inside(b, plane);
        if (da >= 0) out.push_back(a);
        if ((da >= 0) != (db >= 0)) out.push_back(a + (b - a) * (da / (da - db)));
      }
      poly = std::move(out);
    }
    for (const glm::dvec3& p : poly) r.lo = std::min(r.lo, -p.z), r.hi = std::max(r.hi, -p.z);
  }
  const glm::dvec3 apex = glm::dvec3(glm::inverse(view) * glm::dvec4(0, 0, 0, 1));
  if (glm::all(glm::greaterThanEqual(apex, box.lo)) && glm::all(glm::lessThanEqual(apex, box.hi)))
    r.lo = std::min(r.lo, 0.0), r.hi = std::max(r.hi, 0.0);
  return r;
}

// Far: the farthest visible receiver inside the cone's pyramid. Near: the nearest caster inside
// it, but at least 1e-4 of far, which a caster around the light would otherwise break.
ViewSetup fit_spot(const Light& light, const Bounds& receivers,
                   const std::vector<InstanceBounds>& instances) {
  glm::dvec3 p(light.position), axis = glm::normalize(glm::dvec3(light.direction));
  ViewSetup s;
  s.view = glm::lookAt(p, p + axis, any_up(axis));
  const double tan_half = std::tan(glm::radians(0.5 * double(light.cone_angle_deg)));
  DepthRange r = depth_in_pyramid(receivers, s.view, tan_half);
  if (r.empty()) {  // no visible receiver in the cone: cover whatever is in it
    for (const InstanceBounds& ib : instances) {
      DepthRange d = depth_in_pyramid(ib.world, s.view, tan_half);
      if (!d.empty()) r.lo = std::min(r.lo, d.lo), r.hi = std::max(r.hi, d.hi);
    }
  }
  double far = r.empty() ? 2.0 : std::max(r.hi, 1e-6), near = INFINITY;
  for (const InstanceBounds& ib : instances) {
    if (!ib.casts) continue;
    DepthRange d = depth_in_pyramid(ib.world, s.view, tan_half);
    if (!d.empty() && d.lo <= far) near = std::min(near, d.lo);
  }
  // Receivers nearer than every caster are lit whatever their depth, so only casters count.
  if (near == INFINITY) near = r.empty() ? 1.0 : r.lo;
  near = std::clamp(near * 0.999, far * 1e-4, far);
  far *= 1.001;
  glm::dmat4 proj = glm::perspective(2.0 * std::atan(tan_half), 1.0, near, far);
  s.world_to_ndc = gl_to_texture_ndc() * proj * s.view;
  s.depth = {MapDepth::kPerspective, near, far};
  return s;
}

}  // namespace

int face_of(const CubeFaces& f, const glm::dvec3& x) {
  const glm::dvec4 h = f.space * glm::dvec4(x, 1.0);
  const glm::dvec3 d = glm::dvec3(h) / h.w - f.origin;
  int best = 0;
  double most = d.x * f.inv_pos.x;
  for (int k = 1; k < 6; ++k) {
    const int axis = k / 2;
    const double r = (k % 2) ? -d[axis] * f.inv_neg[axis] : d[axis] * f.inv_pos[axis];
    if (r > most) most = r, best = k;
  }
  return best;
}

ViewSetup camera_setup(const Camera& camera) {
  ViewSetup s;
  s.view = glm::lookAt(glm::dvec3(camera.eye), glm::dvec3(camera.target), glm::dvec3(camera.up));
  glm::dmat4 proj = glm::perspective(glm::radians(double(camera.fov_deg)),
                                     double(camera.width) / double(camera.height),
                                     double(camera.near), double(camera.far));
  s.world_to_ndc = gl_to_texture_ndc() * proj * s.view;
  return s;
}

CameraRays camera_rays(const Camera& c) {
  const glm::dvec3 f = glm::normalize(glm::dvec3(c.target) - glm::dvec3(c.eye));
  const glm::dvec3 r = glm::normalize(glm::cross(f, glm::dvec3(c.up)));
  const glm::dvec3 u = glm::cross(r, f);
  const double tan_y = std::tan(glm::radians(0.5 * double(c.fov_deg)));
  const double tan_x = tan_y * double(c.width) / double(c.height);
  return {glm::vec4(c.eye, 1.0f), glm::vec4(f - tan_x * r + tan_y * u, 0.0),
          glm::vec4(2.0 * tan_x * r, 0.0), glm::vec4(-2.0 * tan_y * u, 0.0)};
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
                            const std::vector<InstanceBounds>& instances, MapFit fit) {
  Bounds receivers = receiver_region(camera, instances, fit);
  return light.type == LightType::kSpot ? fit_spot(light, receivers, instances)
                                        : fit_directional(light, receivers, instances);
}

}  // namespace shadow
