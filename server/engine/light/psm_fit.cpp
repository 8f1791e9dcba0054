#include "engine/light/psm_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/geometry.hpp"
#include "engine/light/post_perspective.hpp"

namespace shadow {
namespace {

glm::dmat4 from_rows(const glm::dvec4& x, const glm::dvec4& y, const glm::dvec4& z,
                     const glm::dvec4& w) {
  return glm::transpose(glm::dmat4(x, y, z, w));
}

glm::dvec3 any_up(const glm::dvec3& forward) {
  const glm::dvec3 a = glm::abs(forward);
  return (a.y < 0.9) ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
}

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

const auto& kFrustum = kClipFrustum;

// The uniform map instead of PSM; a point light has none and needs the cube.
PsmFit uniform_fallback(const Light& light, const Camera& camera,
                        const std::vector<InstanceBounds>& instances, const std::string& why) {
  PsmFit fit;
  if (light.type == LightType::kPoint) {
    fit.needs_cube = true;
    fit.light_case = why + ": needs a cube map";
    return fit;
  }
  fit.setup = fit_uniform_light(light, camera, instances);
  fit.light_case = why + ": uniform";
  return fit;
}

// The camera's post-perspective space set up for a light.
struct PsmSpace {
  PsmFit fit;                    // the virtual camera's numbers, its view and the case so far
  glm::dmat4 clip_v{1.0};        // world -> the virtual camera's GL clip space
  glm::dmat4 virtual_view{1.0};  // world -> the virtual camera's eye space
  PostPerspectiveLight pp;       // the light in post-perspective space
  Bounds receivers;              // the visible receivers' box in post-perspective space
  std::vector<Bounds> casters;   // every caster's world box
  // A lower bound of the distance from a positional light to its nearest caster triangle, if
  // measured (see caster_parts).
  std::optional<double> min_caster_distance;
};

// A perspective light map in post-perspective space: its texture rows and depth range.
struct FrustumDepth {
  glm::dmat4 t{1.0};  // light-view homogeneous -> texture clip space
  double near = 0, far = 0;
  MapDepth depth;  // the point light's ordinary perspective; the inverted one's is kStored
};

// The camera's post-perspective space set up for a light: the virtual camera (near plane pushed,
// slid back as the settings say), the light in it, the visible receivers' box and the casters.
// Empty, with `fallback` set, when there is no visible receiver.
std::optional<PsmSpace> psm_space(const Light& light, const Camera& camera,
                                  const std::vector<InstanceBounds>& instances,
                                  const PsmSettings& settings,
                                  const std::optional<DepthRange>& measured, PsmFit& fallback) {
  const glm::dvec3 eye(camera.eye), fwd = glm::normalize(glm::dvec3(camera.target) - eye);
  const glm::dvec3 up(camera.up);
  const double fovy = glm::radians(double(camera.fov_deg));
  const double aspect = double(camera.width) / double(camera.height);
  const double n = camera.near, f = camera.far;
  const glm::dmat4 view = glm::lookAt(eye, eye + fwd, up);
  const glm::dmat4 clip_cam = glm::perspective(fovy, aspect, n, f) * view;

  // Unit-cube clipping (Kozlov 14.2.1): the visible receivers are each receiver's box clipped
  // to the view frustum; in post-perspective space their box is what the light must cover.
  std::vector<glm::dvec4> cone;  // spot lights: the cone's pyramid
  // The measured depth range (the camera view's receiving pixels) widened by kMeasuredMargin of
  // each end's own distance, plus 1e-6 of the scene's coordinate scale: the G-buffer positions
  // are float ray-plane hits (relative error ~1e-6 of the distance from the eye, plus the
  // rounding of world coordinates far from the origin), and the map is also read between pixel
  // centres (PCF taps, clients). 1e-3 covers both many times over and costs about 0.1% of the
  // post-perspective depth resolution. (A margin in units of the whole range would pull the near
  // plane back by metres when the range is long: 2.96 -> 1.76 m on the street.) Receivers
  // outside the range (hidden parts of the boxes) stay in the light's aim: clipping them to it
  // was measured worse on the street with the light facing the camera (docs/benchmarks.md).
  constexpr double kMeasuredMargin = 1e-3;
  const bool push = settings.near != PsmNear::kCamera;  // kReceivers, kVirtualSlideBack
  const bool use_measured = measured && push && std::isfinite(measured->min) &&
                            std::isfinite(measured->max) && measured->min <= measured->max;
  double measured_near = 0, measured_far = 0;
  if (use_measured) {
    const double coords = 1e-6 * (glm::length(eye) + std::abs(measured->max));
    measured_near = std::max(double(n), measured->min * (1 - kMeasuredMargin) - coords);
    measured_far = measured->max * (1 + kMeasuredMargin) + coords;
  }
  // A spot light lights nothing outside its cone: receivers are also clipped to the cone's
  // pyramid (view space of the spot: |x|, |y| <= -z tan(cone / 2)).
  if (light.type == LightType::kSpot) {
    const glm::dvec3 lp(light.position), la = glm::normalize(glm::dvec3(light.direction));
    const glm::dmat4 spot_view = glm::lookAt(lp, lp + la, any_up(la));
    const double t = std::tan(glm::radians(0.5 * double(light.cone_angle_deg)));
    for (const glm::dvec4& q : {glm::dvec4(-1, 0, -t, 0), glm::dvec4(1, 0, -t, 0),
                                glm::dvec4(0, -1, -t, 0), glm::dvec4(0, 1, -t, 0)})
      cone.push_back(to_world(spot_view, q));
  }
  const std::vector<glm::dvec3> receivers = visible_receiver_points(clip_cam, instances, cone);
  std::vector<Bounds> casters;
  for (const InstanceBounds& ib : instances)
    if (ib.casts) casters.push_back(ib.world);
  if (receivers.empty()) {
    fallback = uniform_fallback(light, camera, instances, "no visible receiver");
    return std::nullopt;
  }

  PsmSpace space;
  PsmFit& fit = space.fit;
  // Slide-back (the paper, section 4.2): only an inverted light needs casters behind the camera;
  // move the virtual camera back until every caster box is at least `near` in front of it.
  const PostPerspectiveLight original = post_perspective_light(light, clip_cam);
  double slide = 0.0;
  if (settings.casters == PsmCasters::kSlideBack &&
      original.kind == PostPerspectiveCase::kInvertedPoint) {
    double dmin = INFINITY;
    for (const Bounds& b : casters)
      for (const glm::dvec3& p : b.corners()) dmin = std::min(dmin, glm::dot(p - eye, fwd));
    if (std::isfinite(dmin)) slide = std::max(0.0, n - dmin);
  }
  const glm::dvec3 veye = eye - slide * fwd;
  double rmin = INFINITY, rmax = -INFINITY;
  for (const glm::dvec3& p : receivers) {
    const double d = glm::dot(p - veye, fwd);
    rmin = std::min(rmin, d), rmax = std::max(rmax, d);
  }
  double vn = n + slide, vf = f + slide;
  if (use_measured) {  // near-plane push to the measured receivers (the paper §6)
    vn = std::max(vn, measured_near + slide);
    vf = std::min(vf, measured_far + slide);
  } else if (push) {  // bounding volumes (Kozlov 14.1.2)
    vn = std::max(vn, 0.999 * rmin);
    vf = std::min(vf, 1.001 * rmax);
  }
  vf = std::max(vf, vn * 1.01);
  // Virtual slide-back (Kozlov 14.1.2, Fig 14-6): back by v, near and far by v further, and the
  // field of view narrowed so that the near-plane quad (half-height vn tan(fovy / 2)) stays put.
  double vfovy = fovy, vslide = 0;
  if (settings.near == PsmNear::kVirtualSlideBack) {
    vslide = settings.virtual_slide > 0 ? settings.virtual_slide : vn;
    vfovy = 2.0 * std::atan(vn * std::tan(0.5 * fovy) / (vn + vslide));
    vn += vslide, vf += vslide;
  }
  const glm::dvec3 veye2 = veye - vslide * fwd;
  const glm::dmat4 vview = glm::lookAt(veye2, veye2 + fwd, up);
  const glm::dmat4 clip_v = glm::perspective(vfovy, aspect, vn, vf) * vview;
  fit.virtual_near = vn, fit.virtual_far = vf, fit.slide_back = slide + vslide;
  fit.virtual_slide = vslide, fit.virtual_fovy_deg = glm::degrees(vfovy);
  fit.setup.view = vview;

  if (!finite(clip_v) || !(vf > vn)) {
    fallback = uniform_fallback(light, camera, instances, "degenerate virtual camera");
    return std::nullopt;
  }
  const PostPerspectiveLight pp = post_perspective_light(light, clip_v);
  space.pp = pp;
  fit.light_case = pp.description;
  if (vslide > 0) fit.light_case += " (virtual slide-back)";
  Bounds& r = space.receivers;  // all in front of the virtual camera
  for (const glm::dvec3& p : receivers) {
    const glm::dvec4 q = clip_v * glm::dvec4(p, 1.0);
    r.extend(glm::dvec3(q) / q.w);
  }

  space.clip_v = clip_v;
  space.virtual_view = vview;
  space.casters = std::move(casters);
  return space;
}

// Whether a caster's box holds a positional light (a lamp in a room that is one mesh).
bool holds_light(const Bounds& b, const Light& light) {
  return light.type != LightType::kDirectional && b.contains(glm::dvec3(light.position));
}

// The boxes whose clipped surface vertices stand for caster box `b` in the near-plane search.
// A box that holds the light may hold geometry arbitrarily near it, which no clipped surface
// vertex shows. With the measured distance r to the nearest caster triangle that geometry lies
// outside the ball of radius r around the light, so outside the cube of half-edge r / sqrt(3)
// inscribed in it: the box stands for its parts beyond that cube's sides (up to six boxes).
// Unmeasured, it stands for itself and the caller clips at 1e-4 of the receivers' depth.
std::vector<Bounds> caster_parts(const PsmSpace& s, const Light& light, const Bounds& b) {
  if (!holds_light(b, light) || !s.min_caster_distance) return {b};
  const glm::dvec3 p(light.position);
  const double h = 0.999 * *s.min_caster_distance / std::sqrt(3.0);
  std::vector<Bounds> parts;
  for (int a = 0; a < 3; ++a) {
    Bounds below = b, above = b;
    below.hi[a] = p[a] - h, above.lo[a] = p[a] + h;
    for (const Bounds& part : {below, above})
      if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

// Every clipped surface vertex of the casters (caster_parts) in the light's view, lv * v, with
// whether it stands for a box around the light whose parts the measured distance bounds.
template <class F>
void for_each_caster_vertex(const PsmSpace& s, const Light& light,
                            const std::vector<glm::dvec4>& planes, const glm::dmat4& lv, F f) {
  for (const Bounds& bx : s.casters) {
    const bool held = s.min_caster_distance && holds_light(bx, light);
    for (const Bounds& part : caster_parts(s, light, bx))
      for_each_clipped_vertex(part, planes, [&](const glm::dvec4& v) { f(lv * v, held); });
  }
}

// Whether a box around the light may hold a caster touching it: no distance was measured.
bool may_touch_light(const PsmSpace& s, const Light& light) {
  return !s.min_caster_distance &&
         std::any_of(s.casters.begin(), s.casters.end(),
                     [&](const Bounds& b) { return holds_light(b, light); });
}

// The texture rows of a perspective map from the post-perspective light (lview looks from it)
// over the pyramid l <= x/z <= rr, b <= y/z <= tp: receivers at light depth [zmin, zmax] and
// every caster in the pyramid that can shadow them, for a point light (depth grows away from
// it) or an inverted one (depth through infinity, Kozlov's inverse projection).
FrustumDepth perspective_depth(const PsmSpace& s, const Light& light, const glm::dmat4& lview,
                               double l, double rr, double b, double tp, double zmin, double zmax) {
  FrustumDepth out;
  const glm::dmat4 lv = lview * s.clip_v;
  // The receivers' pyramid from L: homogeneous, so behind the camera (w < 0) it selects the
  // mirrored pyramid behind L, which is where an inverted light's casters are.
  std::vector<glm::dvec4> pyramid = {to_world(lv, {1, 0, l, 0}), to_world(lv, {-1, 0, -rr, 0}),
                                     to_world(lv, {0, 1, b, 0}), to_world(lv, {0, -1, -tp, 0}),
                                     to_world(lv, {0, 0, -1, 0})};
  const glm::dvec4 x_row{1 / (rr - l), 0, l / (rr - l), 0};
  const glm::dvec4 y_row{0, -1 / (tp - b), -tp / (tp - b), 0};
  const glm::dvec4 w_row{0, 0, -1, 0};
  if (s.pp.kind == PostPerspectiveCase::kPoint) {
    // Casters lie between L and the receivers, in front of the camera (depth grows towards
    // the light) and at light depth <= zmax.
    std::vector<glm::dvec4> planes = pyramid;
    // A directional light from the front: casters are farther than their receivers, so in
    // front of the near plane. A spot or point light may sit nearer than it: then casters
    // between the light and the near plane count, everything in front of the camera plane.
    planes.push_back(to_world(
        s.clip_v, light.type == LightType::kDirectional ? kFrustum[4] : glm::dvec4(0, 0, 0, 1)));
    planes.push_back(to_world(lv, {0, 0, 1, zmax}));
    // held: the nearest caster in a box around the light, 0 where it may touch L (unmeasured).
    double near = zmin, held = may_touch_light(s, light) ? 0.0 : INFINITY;
    for_each_caster_vertex(s, light, planes, lv, [&](const glm::dvec4& h, bool in_held) {
      double& nearest = in_held ? held : near;
      if (h.w > 0) nearest = std::min(nearest, -h.z / h.w);
    });
    // Casters in a box around the light count from 1e-4 of the receivers' depth on (nearer
    // parts are clipped): a caster touching L would make the map useless; keep near a sane
    // fraction of far. Unmeasured, they start there, and the stored depth 1 - near / z then
    // spans ~1e-4 over the scene: the constant NDC bias (2e-5) alone is ~20% of the distance
    // to the light, which lit receivers up to that far behind their casters (the standard
    // room's PSM_CUBE: 0.27% of its pixels at every map size).
    near = std::min(near, std::max(held, 1e-4 * zmax));
    near = std::max(0.999 * near, 1e-7 * zmax);
    const double far = 1.001 * zmax;
    out.t = from_rows(x_row, y_row, {0, 0, -far / (far - near), -far * near / (far - near)}, w_row);
    out.near = near, out.far = far;
    out.depth = {MapDepth::kPerspective, near, far};
  } else {
    // Inverted: light runs towards L, so depth falls with 1/z: D = (1/z - s) / (1/zmin - s),
    // 1 at the nearest receiver, 0 at the farthest caster, where s = min 1/z over casters in
    // the receivers' pyramid. 1/z is continuous through infinity (0 there): a caster behind
    // the camera lies behind L (z < 0, s = -1/a) and the line wraps through infinity, which
    // with a = zmin is Kozlov's inverse projection, near = -a, far = a (depth (1 + a/z) / 2).
    // Without casters behind the camera (or after the slide-back) s = 1/z_far > 0: a reversed
    // perspective that spends the whole depth range on [zmin, z_far] instead of a half of it,
    // which matters when L is far away (near the parallel case).
    const double zn = 0.999 * zmin;
    double s_min = 1.0 / zmax, s_held = may_touch_light(s, light) ? -INFINITY : INFINITY;
    for_each_caster_vertex(s, light, pyramid, lv, [&](const glm::dvec4& h, bool in_held) {
      double& nearest = in_held ? s_held : s_min;
      // The pyramid keeps w and -z of one sign.
      if (h.z != 0.0) nearest = std::min(nearest, -h.w / h.z);
    });
    // As above, casters in a box around the light count from 1e-4 zmin behind it (without the
    // measured distance, from there); nothing nearer to L than 1e-7 zmin behind it: such a
    // caster would leave no depth range.
    s_min = std::min(s_min, std::max(s_held, -1e4 / zn));
    s_min = std::max(s_min, -1e7 / zn);
    const double sf = s_min - 1e-4 * (1.0 / zn - s_min);  // the farthest caster not on D = 0
    const double k = 1.0 / (1.0 / zn - sf);
    out.t = from_rows(x_row, y_row, {0, 0, k * sf, k}, w_row);
    out.near = sf < 0 ? 1.0 / sf : (sf > 0 ? 1.0 / sf : 1e300), out.far = zn;
  }
  return out;
}

// Near the parallel boundary L runs off to infinity: a perspective frustum from 1e4 box sizes
// away has no float depth resolution left (measured: 78% of texels wrong at 89.99999 deg).
// The rays then diverge by < 1e-4 rad over the box, so an orthographic light along the mean
// ray is within 1e-4 box widths of the true one (0.4 texel at 4096^2).
bool nearly_parallel(const PsmSpace& s) {
  const Bounds& r = s.receivers;
  return glm::length(s.pp.position - 0.5 * (r.lo + r.hi)) >
         1e4 * std::max(glm::length(r.hi - r.lo), 1e-12);
}

// The single PSM map in a post-perspective space.
PsmFit single_map(const PsmSpace& space, const Light& light, const Camera& camera,
                  const std::vector<InstanceBounds>& instances) {
  PsmFit fit = space.fit;
  const Bounds& r = space.receivers;
  const PostPerspectiveLight& pp = space.pp;
  const glm::dmat4 &clip_v = space.clip_v, &vview = space.virtual_view;
  const double vn = fit.virtual_near;
  const std::vector<Bounds>& casters = space.casters;
  glm::dmat4 lview, t;
  const glm::dvec3 c = 0.5 * (r.lo + r.hi);
  glm::dvec3 d = pp.direction;
  bool ortho = pp.kind == PostPerspectiveCase::kDirectional;
  if (!ortho && nearly_parallel(space)) {
    ortho = true;
    d = glm::normalize(pp.kind == PostPerspectiveCase::kPoint ? c - pp.position : pp.position - c);
    fit.light_case += " (nearly parallel: orthographic)";
  }
  if (ortho) {
    // Orthographic in post-perspective space. Casters are clipped to half the virtual near
    // distance: nearer ones sit far out in post-perspective space and would wreck the depth
    // range, and they cannot shadow a receiver at depth >= near along a near-parallel light.
    // Not so for a spot or point light in (or next to) the camera plane: a caster between it
    // and the receivers nearer than vn / 2 is left out of the depth range (known limitation;
    // the camera-plane cases of psm_fit_test and psm_test have no such caster).
    lview = glm::lookAt(c - d, c, any_up(d));
    const Bounds lr = transform_bounds(r, lview);
    glm::dvec2 lo(lr.lo), hi(lr.hi);
    const glm::dvec2 pad = 1e-3 * (hi - lo) + 1e-9;
    lo -= pad, hi += pad;
    const glm::dmat4 lv = lview * clip_v;
    const glm::dvec4 depth_row = glm::transpose(vview)[2];  // view z: -depth
    std::vector<glm::dvec4> planes = {
        -depth_row - glm::dvec4(0, 0, 0, 0.5 * vn), to_world(lv, {1, 0, 0, -lo.x}),
        to_world(lv, {-1, 0, 0, hi.x}), to_world(lv, {0, 1, 0, -lo.y}),
        to_world(lv, {0, -1, 0, hi.y})};
    double near = -lr.hi.z, far = -lr.lo.z;
    for (const Bounds& b : casters)
      for_each_clipped_vertex(b, planes, [&](const glm::dvec4& v) {
        const glm::dvec4 h = lv * v;
        if (h.w > 0) near = std::min(near, -h.z / h.w);
      });
    const double pad_z = 1e-3 * (far - near) + 1e-9;
    near -= pad_z, far += pad_z;
    t = from_rows({1 / (hi.x - lo.x), 0, 0, -lo.x / (hi.x - lo.x)},
                  {0, -1 / (hi.y - lo.y), 0, hi.y / (hi.y - lo.y)},
                  {0, 0, -1 / (far - near), -near / (far - near)}, {0, 0, 0, 1});
    fit.light_near = near, fit.light_far = far;
  } else {
    // A point light at L: look from L at the receivers' box (the mean direction to its corners).
    const glm::dvec3 L = pp.position;
    const std::array<glm::dvec3, 8> corners = r.corners();
    glm::dvec3 sum(0.0);
    for (const glm::dvec3& p : corners) sum += glm::normalize(p - L);
    glm::dvec3 axis = glm::normalize(sum);
    double worst = INFINITY;
    for (const glm::dvec3& p : corners)
      worst = std::min(worst, glm::dot(glm::normalize(p - L), axis));
    // L lies on the plane at infinity (z > 1 >= every receiver), so -z always sees them all.
    if (!(worst > 1e-3) && L.z > r.hi.z) {
      axis = glm::dvec3(0, 0, -1);
      worst = INFINITY;
      for (const glm::dvec3& p : corners) worst = std::min(worst, -glm::normalize(p - L).z);
    }
    // A spot or point light whose post-perspective position lies inside the receivers' box, or
    // so close that one frustum would need more than 2 x kMaxHalfAngleDeg, cannot be covered by
    // a single map: cube faces for a point light, the uniform spot map for a spot light.
    constexpr double kMaxHalfAngleDeg = 80.0;
    if (light.type != LightType::kDirectional &&
        !(worst > std::cos(glm::radians(kMaxHalfAngleDeg)))) {
      const std::string why = pp.description + ", inside or next to the receivers' box";
      PsmFit f =
          uniform_fallback(light, camera, instances,
                           light.type == LightType::kSpot ? why + ": needs a cube map; spot" : why);
      f.needs_cube = true;
      return f;
    }
    lview = glm::lookAt(L, L + axis, any_up(axis));
    double l = INFINITY, rr = -INFINITY, b = INFINITY, tp = -INFINITY, zmin = INFINITY,
           zmax = -INFINITY;
    for (const glm::dvec3& p : corners) {
      const glm::dvec3 v = glm::dvec3(lview * glm::dvec4(p, 1.0));
      const double z = -v.z;
      l = std::min(l, v.x / z), rr = std::max(rr, v.x / z);
      b = std::min(b, v.y / z), tp = std::max(tp, v.y / z);
      zmin = std::min(zmin, z), zmax = std::max(zmax, z);
    }
    const double px = 1e-3 * (rr - l) + 1e-9, py = 1e-3 * (tp - b) + 1e-9;
    l -= px, rr += px, b -= py, tp += py;
    const FrustumDepth depth = perspective_depth(space, light, lview, l, rr, b, tp, zmin, zmax);
    t = depth.t;
    fit.light_near = depth.near, fit.light_far = depth.far;
    fit.setup.depth = depth.depth;
  }
  fit.setup.world_to_ndc = t * lview * clip_v;
  if (!finite(fit.setup.world_to_ndc))
    return uniform_fallback(light, camera, instances, fit.light_case + ", degenerate fit");
  return fit;
}

}  // namespace

bool caster_box_holds_light(const Light& light, const std::vector<InstanceBounds>& instances) {
  return std::any_of(instances.begin(), instances.end(), [&](const InstanceBounds& ib) {
    return ib.casts && holds_light(ib.world, light);
  });
}

PsmFit fit_psm_light(const Light& light, const Camera& camera,
                     const std::vector<InstanceBounds>& instances, const PsmSettings& settings,
                     const std::optional<DepthRange>& measured,
                     std::optional<double> min_caster_distance) {
  PsmFit fallback;
  std::optional<PsmSpace> space = psm_space(light, camera, instances, settings, measured, fallback);
  if (!space) return fallback;
  space->min_caster_distance = min_caster_distance;
  return single_map(*space, light, camera, instances);
}

PsmCubeFit fit_psm_cube(const Light& light, const Camera& camera,
                        const std::vector<InstanceBounds>& instances, const PsmSettings& settings,
                        const std::optional<DepthRange>& measured, uint32_t map_size,
                        uint32_t guard, std::optional<double> min_caster_distance) {
  PsmCubeFit out;
  std::optional<PsmSpace> found = psm_space(light, camera, instances, settings, measured, out.fit);
  if (!found) return out;
  found->min_caster_distance = min_caster_distance;
  const PsmSpace& s = *found;
  const Bounds& r = s.receivers;
  const glm::dvec3 L = s.pp.position;
  // Parallel (or nearly so) in post-perspective space: one orthographic map already has the same
  // texel size everywhere on the receivers.
  if (s.pp.kind == PostPerspectiveCase::kDirectional || nearly_parallel(s)) {
    out.fit = single_map(s, light, camera, instances);
    out.fit.light_case += " (parallel in post-perspective space: one map, no cube)";
    return out;
  }
  out.cube = true;
  out.fit = s.fit;
  // Distances from L to the cube's sides along their outward normals; a side faces away from
  // the light (and is used) when L is strictly inside its plane.
  CubeFaces select;
  select.space = s.clip_v;
  select.origin = L;
  for (int a = 0; a < 3; ++a) {
    const double pos = 1.0 - L[a], neg = 1.0 + L[a];
    select.inv_pos[a] = pos > 1e-9 ? 1.0 / pos : 0.0;
    select.inv_neg[a] = neg > 1e-9 ? 1.0 / neg : 0.0;
  }
  const double widen = double(guard) / (double(map_size) - 2.0 * guard);
  out.texel_min = INFINITY, out.texel_max = 0;
  int used = 0;
  for (int k = 0; k < 6; ++k) {
    CubeFaceFit& face = out.faces[k];
    face.setup.view = s.virtual_view;
    face.setup.faces = select;
    face.setup.faces.owned = 1u << k;
    face.setup.world_to_ndc = glm::dmat4(0.0);  // an empty map until rendered
    const int a = k / 2;
    const double side = (k % 2) ? -1.0 : 1.0;
    const double dist = side > 0 ? 1.0 - L[a] : 1.0 + L[a];
    if (!(dist > 1e-9)) {
      face.reason = "faces the light";
      continue;
    }
    ++used;
    const glm::dmat4 lview = glm::lookAt(L, L + cube_face_axis(k), cube_face_up(k));
    // The side's square seen from L, and the pyramid through its edges.
    double sl = INFINITY, sr = -INFINITY, sb = INFINITY, st = -INFINITY;
    for (double u : {-1.0, 1.0})
      for (double v : {-1.0, 1.0}) {
        glm::dvec3 p(0.0);
        p[a] = side, p[(a + 1) % 3] = u, p[(a + 2) % 3] = v;
        const glm::dvec3 q = glm::dvec3(lview * glm::dvec4(p, 1.0));
        sl = std::min(sl, -q.x / q.z), sr = std::max(sr, -q.x / q.z);
        sb = std::min(sb, -q.y / q.z), st = std::max(st, -q.y / q.z);
      }
    const std::vector<glm::dvec4> pyramid = {
        to_world(lview, {1, 0, sl, 0}), to_world(lview, {-1, 0, -sr, 0}),
        to_world(lview, {0, 1, sb, 0}), to_world(lview, {0, -1, -st, 0})};
    // Unit-cube clipping per face: the part of the receivers' box seen through this side.
    double l = INFINITY, rr = -INFINITY, b = INFINITY, tp = -INFINITY, zmin = INFINITY,
           zmax = -INFINITY;
    for_each_clipped_vertex(r, pyramid, [&](const glm::dvec4& v) {
      const glm::dvec3 q = glm::dvec3(lview * v) / v.w;
      const double z = -q.z;
      if (!(z > 0)) return;
      l = std::min(l, q.x / z), rr = std::max(rr, q.x / z);
      b = std::min(b, q.y / z), tp = std::max(tp, q.y / z);
      zmin = std::min(zmin, z), zmax = std::max(zmax, z);
    });
    if (!(l < rr && b < tp)) {
      face.reason = "no visible receiver through this side";
      continue;
    }
    l = std::max(l, sl), rr = std::min(rr, sr), b = std::max(b, sb), tp = std::min(tp, st);
    const double pu = widen * (rr - l) + 1e-12, pv = widen * (tp - b) + 1e-12;
    l -= pu, rr += pu, b -= pv, tp += pv;
    const FrustumDepth depth = perspective_depth(s, light, lview, l, rr, b, tp, zmin, zmax);
    face.setup.world_to_ndc = depth.t * lview * s.clip_v;
    if (!finite(face.setup.world_to_ndc)) {
      face.setup.world_to_ndc = glm::dmat4(0.0);
      face.reason = "degenerate fit";
      continue;
    }
    face.rendered = true;
    face.near = depth.near, face.far = depth.far;
    face.setup.depth = depth.depth;
    // Texels on the side's plane (at distance dist from L), as a fraction of the edge (2).
    const double tu = (rr - l) * dist / map_size / 2.0, tv = (tp - b) * dist / map_size / 2.0;
    out.texel_min = std::min({out.texel_min, tu, tv});
    out.texel_max = std::max({out.texel_max, tu, tv});
    char what[96];
    std::snprintf(what, sizeof what, "receivers cover %.0f%% x %.0f%% of this side",
                  100.0 * (rr - l - 2 * pu) / (sr - sl), 100.0 * (tp - b - 2 * pv) / (st - sb));
    face.reason = what;
  }
  if (out.texel_max == 0) out.texel_min = 0;
  out.fit.light_case += ": cube faces on " + std::to_string(used) + " sides of the unit cube";
  return out;
}

}  // namespace shadow
