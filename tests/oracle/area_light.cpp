#include "oracle/area_light.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "oracle/parallel.hpp"

namespace shadow::oracle {
namespace {

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

uint64_t splitmix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Counter-based uniform in [0, 1): results do not depend on thread scheduling.
struct Rng {
  uint64_t state;
  double next() {
    state = splitmix(state);
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  }
};

// Any orthonormal pair perpendicular to unit n.
void basis(const glm::dvec3& n, glm::dvec3& t1, glm::dvec3& t2) {
  t1 = glm::normalize(std::abs(n.x) < 0.9 ? glm::cross(n, glm::dvec3(1, 0, 0))
                                          : glm::cross(n, glm::dvec3(0, 1, 0)));
  t2 = glm::cross(n, t1);
}

}  // namespace

glm::dvec2 square_to_disk(glm::dvec2 u) {
  const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
  if (a == 0.0 && b == 0.0) return {0.0, 0.0};
  const double quarter = std::numbers::pi / 4.0;
  double r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = quarter * (b / a);
  } else {
    r = b;
    phi = 2.0 * quarter - quarter * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

AreaVisibility area_visibility(const RayOracle& oracle, const Light& light,
                               std::span<const glm::dvec3> points,
                               std::span<const glm::dvec3> normals,
                               std::span<const uint8_t> receives, const AreaLightOptions& options) {
  if (normals.size() != points.size() || (!receives.empty() && receives.size() != points.size())) {
    throw std::invalid_argument("oracle: points, normals and receives differ in length");
  }
  if (options.min_grid == 0 || options.max_grid < options.min_grid) {
    throw std::invalid_argument("oracle: need 0 < min_grid <= max_grid");
  }
  const double offset =
      std::max(options.offset_scale * oracle.scene_diagonal(), oracle.min_ray_offset());
  const glm::dvec3 centre(light.position);
  const glm::dvec3 axis = glm::normalize(glm::dvec3(light.direction));
  const double cos_half_cone = std::cos(glm::radians(0.5 * double{light.cone_angle_deg}));
  const bool directional = light.type == LightType::kDirectional;
  // Disk radius: world units for local lights, tan(half angle) at unit distance for the sun.
  const double radius =
      directional ? std::tan(glm::radians(0.5 * double{light.size})) : double{light.size};
  glm::dvec3 a1, a2;  // the disk's plane for directional and spot lights
  basis(axis, a1, a2);

  AreaVisibility out;
  out.visibility.assign(points.size(), std::numeric_limits<float>::quiet_NaN());
  std::atomic<size_t> unconverged{0};
  std::atomic<uint64_t> rays{0};

  parallel_for(points.size(), [&](size_t begin, size_t end) {
    uint64_t local_rays = 0;
    size_t local_unconverged = 0;
    for (size_t i = begin; i < end; ++i) {
      const glm::dvec3 p = points[i];
      if (!finite(p)) continue;
      if (!directional) {
        const glm::dvec3 v = centre - p;
        const double dist = glm::length(v);
        if (dist == 0.0) {
          out.visibility[i] = 1.0f;
          continue;
        }
        if (light.type == LightType::kSpot && glm::dot(-v / dist, axis) < cos_half_cone) {
          out.visibility[i] = 0.0f;  // outside the cone, or behind the light
          continue;
        }
      }
      const bool ignores_occluders = !receives.empty() && receives[i] == 0;
      if (ignores_occluders) {
        out.visibility[i] = 1.0f;
        continue;
      }
      glm::dvec3 n = normals[i];
      if (!finite(n)) n = glm::dvec3(0.0);
      const glm::dvec3 to_centre = directional ? -axis : glm::normalize(centre - p);
      if (!options.seen_side && glm::dot(n, to_centre) < 0.0) n = -n;  // face the light
      const glm::dvec3 org = p + offset * n;
      glm::dvec3 d1 = a1, d2 = a2;
      if (light.type == LightType::kPoint) basis(to_centre, d1, d2);

      // Whether the light is seen along the disk point u in [0, 1)^2.
      auto lit = [&](glm::dvec2 u) {
        const glm::dvec2 d = radius * square_to_disk(u);
        glm::dvec3 dir;
        double dist = std::numeric_limits<double>::infinity();
        if (directional) {
          dir = glm::normalize(-axis + d.x * d1 + d.y * d2);
        } else {
          const glm::dvec3 v = centre + d.x * d1 + d.y * d2 - org;
          dist = glm::length(v);
          if (!(dist > 0.0)) return true;
          dir = v / dist;
        }
        if (glm::dot(dir, n) <= 0.0) return false;  // below the surface's horizon
        return !oracle.occluded(org, dir, dist);
      };

      // Two jittered samples per stratum of a g x g grid. For stratified sampling the mean's
      // variance is sum_s p_s (1 - p_s) / (2 N^2); each stratum whose two samples differ is an
      // unbiased estimate of 2 p_s (1 - p_s), so the standard error is sqrt(differing) / (2 N).
      Rng rng{splitmix(options.seed ^ splitmix(i + 0x51ed270b27ull))};
      double v = 0.0;
      bool converged = false;
      for (uint32_t g = options.min_grid;; g = std::min(2 * g, options.max_grid)) {
        uint32_t hits = 0, differing = 0;
        for (uint32_t sy = 0; sy < g; ++sy) {
          for (uint32_t sx = 0; sx < g; ++sx) {
            const bool a = lit({(sx + rng.next()) / g, (sy + rng.next()) / g});
            const bool b = lit({(sx + rng.next()) / g, (sy + rng.next()) / g});
            hits += a + b;
            differing += a != b;
          }
        }
        const double samples = 2.0 * g * g;
        local_rays += 2 * uint64_t{g} * g;
        v = hits / samples;
        // Four standard errors inside the tolerance (three let 1 in 64 points exceed it).
        // All-agreeing strata give zero: min_grid must be fine enough that a partly blocked disk
        // rarely hides between samples.
        if (radius == 0.0 || 4.0 * std::sqrt(double(differing)) / samples <= options.tolerance) {
          converged = true;
          break;
        }
        if (g == options.max_grid) break;
      }
      if (!converged) ++local_unconverged;
      out.visibility[i] = static_cast<float>(v);
    }
    rays += local_rays;
    unconverged += local_unconverged;
  });
  out.rays = rays;
  out.unconverged = unconverged;
  return out;
}

AreaVisibility camera_area_visibility(const RayOracle& oracle, const Camera& camera,
                                      const Light& light, const AreaLightOptions& options) {
  const CameraHits hits = oracle.cast_camera(camera);
  std::vector<uint8_t> receives(hits.size(), 1);
  for (size_t i = 0; i < hits.size(); ++i) {
    if (hits.hit(i)) receives[i] = oracle.scene().instances[hits.instance[i]].receives_shadows;
  }
  AreaLightOptions seen = options;
  seen.seen_side = true;
  return area_visibility(oracle, light, hits.position, hits.normal, receives, seen);
}

}  // namespace shadow::oracle
