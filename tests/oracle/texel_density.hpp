// Double-precision reference for the perspective-aliasing measure (PRODUCT_TEXEL_DENSITY) and
// its summary statistics, shared by the tests and shadow-bench.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "oracle/oracle.hpp"

namespace shadow::oracle {

// The size in pixels of one shadow-map texel's footprint at surface point p with normal n: the
// larger singular value of J_camera * inverse(J_light), where J maps a tangent-plane step to
// map texels (light) or image pixels (camera) through each world -> NDC matrix. NaN when p is
// outside the map (w <= 0 or x, y outside [0, 1)); +inf when the light grazes the surface.
double texel_footprint(const glm::dmat4& light_to_ndc, uint32_t map_size,
                       const glm::dmat4& camera_to_ndc, uint32_t width, uint32_t height,
                       const glm::dvec3& p, const glm::dvec3& n);

// texel_footprint at every camera hit (NaN where the camera sees nothing).
std::vector<double> texel_density(const CameraHits& hits, const glm::dmat4& light_to_ndc,
                                  uint32_t map_size, const glm::dmat4& camera_to_ndc);

struct DensityStats {
  size_t pixels = 0;  // non-NaN values (inf counts: the worst aliasing)
  double median = 0.0;
  double p95 = 0.0;
  double fraction_above_1 = 0.0;  // under-sampled: a texel spans more than one pixel
  std::string summary() const;
};

// Percentiles by the nearest-rank rule on the sorted non-NaN values.
DensityStats density_stats(std::span<const float> density);

}  // namespace shadow::oracle
