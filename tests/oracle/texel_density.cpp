#include "oracle/texel_density.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace shadow::oracle {
namespace {

// d(ndc.xy) / dt at clip point c, scaled to texels or pixels.
glm::dvec2 ndc_step(const glm::dmat4& m, const glm::dvec4& c, const glm::dvec3& t,
                    glm::dvec2 scale) {
  const glm::dvec4 mt = m * glm::dvec4(t, 0.0);
  return (glm::dvec2(mt) - glm::dvec2(c) / c.w * mt.w) / c.w * scale;
}

}  // namespace

double texel_footprint(const glm::dmat4& light_to_ndc, uint32_t map_size,
                       const glm::dmat4& camera_to_ndc, uint32_t width, uint32_t height,
                       const glm::dvec3& p, const glm::dvec3& n_in) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const glm::dvec4 cl = light_to_ndc * glm::dvec4(p, 1.0);
  if (!(cl.w > 0.0)) return kNaN;
  const glm::dvec2 s = glm::dvec2(cl) / cl.w;
  if (!(s.x >= 0.0 && s.y >= 0.0 && s.x < 1.0 && s.y < 1.0)) return kNaN;
  const glm::dvec3 n = glm::normalize(n_in);
  const glm::dvec3 t1 = glm::normalize(std::abs(n.x) < 0.9 ? glm::cross(n, glm::dvec3(1, 0, 0))
                                                           : glm::cross(n, glm::dvec3(0, 1, 0)));
  const glm::dvec3 t2 = glm::cross(n, t1);
  const glm::dvec2 texels(map_size, map_size), pixels(width, height);
  const glm::dvec4 cc = camera_to_ndc * glm::dvec4(p, 1.0);
  const glm::dvec2 l1 = ndc_step(light_to_ndc, cl, t1, texels);
  const glm::dvec2 l2 = ndc_step(light_to_ndc, cl, t2, texels);
  const glm::dvec2 c1 = ndc_step(camera_to_ndc, cc, t1, pixels);
  const glm::dvec2 c2 = ndc_step(camera_to_ndc, cc, t2, pixels);
  // A = [c1 c2] * inverse([l1 l2]) maps a texel step to pixels; its columns:
  const double det = l1.x * l2.y - l2.x * l1.y;
  if (det == 0.0) return std::numeric_limits<double>::infinity();
  const glm::dvec2 a1 = (c1 * l2.y - c2 * l1.y) / det, a2 = (c2 * l1.x - c1 * l2.x) / det;
  // The larger singular value of [a1 a2].
  return 0.5 * (std::hypot(a1.x + a2.y, a1.y - a2.x) + std::hypot(a1.x - a2.y, a1.y + a2.x));
}

std::vector<double> texel_density(const CameraHits& hits, const glm::dmat4& light_to_ndc,
                                  uint32_t map_size, const glm::dmat4& camera_to_ndc) {
  std::vector<double> out(hits.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < hits.size(); ++i) {
    if (!hits.hit(i)) continue;
    out[i] = texel_footprint(light_to_ndc, map_size, camera_to_ndc, hits.width, hits.height,
                             hits.position[i], hits.normal[i]);
  }
  return out;
}

DensityStats density_stats(std::span<const float> density) {
  std::vector<float> v;
  v.reserve(density.size());
  for (float x : density)
    if (!std::isnan(x)) v.push_back(x);
  DensityStats s;
  s.pixels = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto rank = [&](double q) {
    const size_t k = static_cast<size_t>(std::ceil(q * v.size()));
    return double{v[std::clamp<size_t>(k, 1, v.size()) - 1]};
  };
  s.median = rank(0.5);
  s.p95 = rank(0.95);
  const auto above = v.end() - std::upper_bound(v.begin(), v.end(), 1.0f);
  s.fraction_above_1 = static_cast<double>(above) / v.size();
  return s;
}

std::string DensityStats::summary() const {
  char buf[160];
  std::snprintf(buf, sizeof buf, "texel size in pixels: median %.3g, p95 %.3g, %.2f%% > 1 (%zu px)",
                median, p95, 100.0 * fraction_above_1, pixels);
  return buf;
}

}  // namespace shadow::oracle
