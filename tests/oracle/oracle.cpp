#include "oracle/oracle.hpp"

#include "oracle/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include <embree3/rtcore.h>

namespace shadow::oracle {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
// Ray masks: every instance is visible to camera rays, only casters to light and map rays.
constexpr unsigned kMaskCaster = 1;
constexpr unsigned kMaskVisible = 2;

// A world-space triangle in double precision: Embree picks the triangle, this gives the exact
// point where the (double) line meets its plane.
struct Plane {
  glm::dvec3 v0;
  glm::dvec3 n;  // unnormalized cross(v1 - v0, v2 - v0), so its sign follows the winding
};

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Intersect context that records every hit and rejects it, so traversal visits the whole ray.
struct CollectContext {
  RTCIntersectContext base;  // first member: Embree hands back a pointer to it
  std::vector<std::pair<uint32_t, uint32_t>>* hits;
};

void collect_all(const RTCFilterFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<CollectContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    ctx->hits->emplace_back(RTCHitN_geomID(args->hit, args->N, i),
                            RTCHitN_primID(args->hit, args->N, i));
    args->valid[i] = 0;
  }
}

RTCRayHit make_ray(const glm::dvec3& org, const glm::dvec3& dir, float tnear, float tfar,
                   unsigned mask) {
  RTCRayHit rh{};
  rh.ray.org_x = static_cast<float>(org.x);
  rh.ray.org_y = static_cast<float>(org.y);
  rh.ray.org_z = static_cast<float>(org.z);
  rh.ray.dir_x = static_cast<float>(dir.x);
  rh.ray.dir_y = static_cast<float>(dir.y);
  rh.ray.dir_z = static_cast<float>(dir.z);
  rh.ray.tnear = tnear;
  rh.ray.tfar = tfar;
  rh.ray.mask = mask;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

}  // namespace

struct RayOracle::Impl {
  Scene scene;
  RTCDevice device = nullptr;
  RTCScene rtc = nullptr;
  std::vector<std::vector<Plane>> planes;  // per instance, per triangle
  glm::dvec3 lo{std::numeric_limits<double>::max()};
  glm::dvec3 hi{std::numeric_limits<double>::lowest()};

  explicit Impl(const Scene& s) : scene(s) {
    device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("oracle: rtcNewDevice failed");
    rtc = rtcNewScene(device);
    rtcSetSceneFlags(rtc, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    planes.resize(scene.instances.size());
    for (size_t k = 0; k < scene.instances.size(); ++k) add_instance(k);
    rtcCommitScene(rtc);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
      throw std::runtime_error("oracle: Embree scene build failed");
    }
  }

  ~Impl() {
    if (rtc) rtcReleaseScene(rtc);
    if (device) rtcReleaseDevice(device);
  }

  void add_instance(size_t k) {
    const Instance& inst = scene.instances[k];
    if (inst.mesh >= scene.meshes.size()) {
      throw std::invalid_argument("oracle: instance " + std::to_string(k) + " names no mesh");
    }
    const Mesh& mesh = scene.meshes[inst.mesh];
    const size_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
    if (nv == 0 || nt == 0) return;
    const glm::dmat4 xf(inst.transform);
    std::vector<glm::dvec3> world(nv);
    for (size_t v = 0; v < nv; ++v) {
      const glm::dvec4 p(mesh.positions[3 * v], mesh.positions[3 * v + 1],
                         mesh.positions[3 * v + 2], 1.0);
      const glm::dvec4 w = xf * p;
      world[v] = glm::dvec3(w) / w.w;
      lo = glm::min(lo, world[v]);
      hi = glm::max(hi, world[v]);
    }
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
    for (size_t v = 0; v < nv; ++v) {
      for (int c = 0; c < 3; ++c) vb[3 * v + c] = static_cast<float>(world[v][c]);
    }
    auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), nt));
    planes[k].resize(nt);
    for (size_t t = 0; t < nt; ++t) {
      uint32_t idx[3];
      for (int c = 0; c < 3; ++c) {
        idx[c] = mesh.indices[3 * t + c];
        if (idx[c] >= nv) throw std::invalid_argument("oracle: index out of range");
        ib[3 * t + c] = idx[c];
      }
      const glm::dvec3 &a = world[idx[0]], &b = world[idx[1]], &c = world[idx[2]];
      planes[k][t] = {a, glm::cross(b - a, c - a)};
    }
    rtcSetGeometryMask(geom, kMaskVisible | (inst.casts_shadows ? kMaskCaster : 0u));
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(rtc, geom, static_cast<unsigned>(k));
    rtcReleaseGeometry(geom);
  }

  double diagonal() const { return hi.x >= lo.x ? glm::length(hi - lo) : 0.0; }
  double largest_coordinate() const {
    if (hi.x < lo.x) return 0.0;
    const glm::dvec3 m = glm::max(glm::abs(lo), glm::abs(hi));
    return std::max({m.x, m.y, m.z});
  }

  // Parameter t where org + t * dir meets the plane of triangle (k, t); NaN if parallel.
  double plane_t(uint32_t k, uint32_t tri, const glm::dvec3& org, const glm::dvec3& dir) const {
    const Plane& p = planes[k][tri];
    const double denom = glm::dot(p.n, dir);
    if (denom == 0.0) return kNaN;
    return glm::dot(p.n, p.v0 - org) / denom;
  }

  void collect(const glm::dvec3& org, const glm::dvec3& dir, unsigned mask,
               std::vector<std::pair<uint32_t, uint32_t>>& hits) const {
    CollectContext ctx;
    rtcInitIntersectContext(&ctx.base);
    ctx.base.filter = collect_all;
    ctx.hits = &hits;
    RTCRayHit rh = make_ray(org, dir, 0.0f, kInf, mask);
    rtcIntersect1(rtc, &ctx.base, &rh);
  }

  bool occluded(const glm::dvec3& org, const glm::dvec3& dir, float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh = make_ray(org, dir, 0.0f, tfar, kMaskCaster);
    rtcOccluded1(rtc, &ctx, &rh.ray);
    return rh.ray.tfar < 0.0f;
  }
};

RayOracle::RayOracle(const Scene& scene) : impl_(std::make_unique<Impl>(scene)) {}
RayOracle::~RayOracle() = default;

bool RayOracle::occluded(const glm::dvec3& origin, const glm::dvec3& direction,
                         double max_distance) const {
  return impl_->occluded(origin, direction,
                         std::isfinite(max_distance) ? static_cast<float>(max_distance) : kInf);
}

double RayOracle::scene_diagonal() const {
  return impl_->diagonal();
}
double RayOracle::min_ray_offset() const {
  return 16.0 * std::numeric_limits<float>::epsilon() * impl_->largest_coordinate();
}
const Scene& RayOracle::scene() const {
  return impl_->scene;
}

double RayOracle::texel_depth(const glm::dmat4& m, const glm::dmat4& inv, double x, double y,
                              const DepthOptions& options) const {
  // The texel's line through the two homogeneous points at NDC z = 0 and z = 1. Either may lie
  // at infinity, and the part with z in [0, 1] may wrap through infinity, so rays go both ways
  // from a finite point and the NDC z of every hit decides.
  const glm::dvec4 a = inv * glm::dvec4(x, y, 0.0, 1.0);
  const glm::dvec4 b = inv * glm::dvec4(x, y, 1.0, 1.0);
  auto is_finite_point = [](const glm::dvec4& h) {
    return std::abs(h.w) > 1e-12 * glm::length(glm::dvec3(h));
  };
  glm::dvec3 org, dir;
  if (is_finite_point(a)) {
    org = glm::dvec3(a) / a.w;
    dir = is_finite_point(b) ? glm::dvec3(b) / b.w - org : glm::dvec3(b);
  } else if (is_finite_point(b)) {
    org = glm::dvec3(b) / b.w;
    dir = glm::dvec3(a);
  } else {
    return 1.0;  // the whole line lies at infinity
  }
  const double len = glm::length(dir);
  if (!(len > 0.0) || !finite(org)) return 1.0;
  dir /= len;

  thread_local std::vector<std::pair<uint32_t, uint32_t>> hits;
  hits.clear();
  impl_->collect(org, dir, kMaskCaster, hits);
  impl_->collect(org, -dir, kMaskCaster, hits);
  double best = 1.0;
  bool found = false;
  for (auto [k, tri] : hits) {
    const double t = impl_->plane_t(k, tri, org, dir);
    if (!std::isfinite(t)) continue;
    const glm::dvec4 c = m * glm::dvec4(org + t * dir, 1.0);
    if (options.require_positive_w && !(c.w > 0.0)) continue;
    const double z = c.z / c.w;
    if (z >= 0.0 && z <= 1.0 && (!found || z < best)) {
      best = z;
      found = true;
    }
  }
  return best;
}

std::vector<double> RayOracle::shadow_map_depth(const glm::dmat4& m, uint32_t size,
                                                const DepthOptions& options) const {
  const glm::dmat4 inv = glm::inverse(m);
  std::vector<double> depth(size_t{size} * size, 1.0);
  parallel_for(depth.size(), [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const double x = (static_cast<double>(i % size) + 0.5) / size;
      const double y = (static_cast<double>(i / size) + 0.5) / size;
      depth[i] = texel_depth(m, inv, x, y, options);
    }
  });
  return depth;
}

std::vector<float> RayOracle::hard_visibility(const Light& light,
                                              std::span<const glm::dvec3> points,
                                              std::span<const glm::dvec3> normals,
                                              std::span<const uint8_t> receives,
                                              const VisibilityOptions& options) const {
  if (normals.size() != points.size() || (!receives.empty() && receives.size() != points.size())) {
    throw std::invalid_argument("oracle: points, normals and receives differ in length");
  }
  const double offset = std::max(options.offset_scale * impl_->diagonal(), min_ray_offset());
  const glm::dvec3 light_pos(light.position);
  const glm::dvec3 axis = glm::normalize(glm::dvec3(light.direction));
  const double cos_half_cone = std::cos(glm::radians(0.5 * double{light.cone_angle_deg}));
  std::vector<float> vis(points.size(), std::numeric_limits<float>::quiet_NaN());
  parallel_for(points.size(), [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const glm::dvec3 p = points[i];
      if (!finite(p)) continue;
      glm::dvec3 to_light = -axis;
      if (light.type != LightType::kDirectional) {
        const glm::dvec3 v = light_pos - p;
        const double dist = glm::length(v);
        if (dist == 0.0) {
          vis[i] = 1.0f;
          continue;
        }
        to_light = v / dist;
        if (light.type == LightType::kSpot && glm::dot(-to_light, axis) < cos_half_cone) {
          vis[i] = 0.0f;  // outside the cone, or behind the light
          continue;
        }
      }
      if (!receives.empty() && receives[i] == 0) {
        vis[i] = 1.0f;
        continue;
      }
      glm::dvec3 n = normals[i];
      if (!finite(n)) n = glm::dvec3(0.0);
      const double facing = glm::dot(n, to_light);
      if (options.seen_side && facing <= 0.0 && n != glm::dvec3(0.0)) {
        vis[i] = 0.0f;  // the seen side faces away from the light, or is edge-on to it
        continue;
      }
      if (facing < 0.0) n = -n;
      const glm::dvec3 org = p + offset * n;
      glm::dvec3 dir = to_light;
      float tfar = kInf;
      if (light.type != LightType::kDirectional) {
        const glm::dvec3 v = light_pos - org;
        const double dist = glm::length(v);
        dir = v / dist;
        tfar = static_cast<float>(dist);
      }
      vis[i] = impl_->occluded(org, dir, tfar) ? 0.0f : 1.0f;
    }
  });
  return vis;
}

CameraHits RayOracle::cast_camera(const Camera& camera) const {
  const uint32_t w = camera.width, h = camera.height;
  CameraHits out;
  out.width = w;
  out.height = h;
  const size_t n = size_t{w} * h;
  out.position.assign(n, glm::dvec3(kNaN));
  out.normal.assign(n, glm::dvec3(kNaN));
  out.instance.assign(n, -1);
  out.triangle.assign(n, -1);

  // GLM lookAt + perspective: a direction with unit component along the view axis has view
  // depth equal to its ray parameter, so [near, far] clips exactly as the rasterizer's planes.
  const glm::dvec3 eye(camera.eye);
  const glm::dvec3 f = glm::normalize(glm::dvec3(camera.target) - eye);
  const glm::dvec3 s = glm::normalize(glm::cross(f, glm::dvec3(camera.up)));
  const glm::dvec3 u = glm::cross(s, f);
  const double tan_half = std::tan(glm::radians(double{camera.fov_deg}) / 2.0);
  const double aspect = static_cast<double>(w) / h;

  parallel_for(n, [&](size_t begin, size_t end) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (size_t i = begin; i < end; ++i) {
      const double x = 2.0 * ((static_cast<double>(i % w) + 0.5) / w) - 1.0;
      const double y = 1.0 - 2.0 * ((static_cast<double>(i / w) + 0.5) / h);
      const glm::dvec3 dir = f + s * (x * tan_half * aspect) + u * (y * tan_half);
      RTCRayHit rh = make_ray(eye, dir, camera.near, camera.far, kMaskVisible);
      rtcIntersect1(impl_->rtc, &ctx, &rh);
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      const uint32_t k = rh.hit.geomID, tri = rh.hit.primID;
      double t = impl_->plane_t(k, tri, eye, dir);
      if (!std::isfinite(t)) t = rh.ray.tfar;
      out.position[i] = eye + t * dir;
      glm::dvec3 nrm = glm::normalize(impl_->planes[k][tri].n);
      out.normal[i] = glm::dot(nrm, dir) > 0.0 ? -nrm : nrm;
      out.instance[i] = static_cast<int32_t>(k);
      out.triangle[i] = static_cast<int32_t>(tri);
    }
  });
  return out;
}

std::vector<float> RayOracle::camera_visibility(const Camera& camera, const Light& light,
                                                const VisibilityOptions& options) const {
  const CameraHits hits = cast_camera(camera);
  std::vector<uint8_t> receives(hits.size(), 1);
  for (size_t i = 0; i < hits.size(); ++i) {
    if (hits.hit(i)) receives[i] = impl_->scene.instances[hits.instance[i]].receives_shadows;
  }
  VisibilityOptions seen = options;
  seen.seen_side = true;
  return hard_visibility(light, hits.position, hits.normal, receives, seen);
}

std::vector<double> shadow_map_depth(const Scene& scene, const glm::mat4& world_to_ndc,
                                     uint32_t size, const DepthOptions& options) {
  return RayOracle(scene).shadow_map_depth(glm::dmat4(world_to_ndc), size, options);
}

std::vector<float> hard_visibility(const Scene& scene, const Light& light,
                                   std::span<const glm::dvec3> points,
                                   std::span<const glm::dvec3> normals,
                                   const VisibilityOptions& options) {
  return RayOracle(scene).hard_visibility(light, points, normals, {}, options);
}

CameraHits cast_camera(const Scene& scene, const Camera& camera) {
  return RayOracle(scene).cast_camera(camera);
}

}  // namespace shadow::oracle
