// Error metrics between an engine product and the oracle's reference, shared by the accuracy
// tests and the benchmarks so both report the same numbers.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "oracle/oracle.hpp"  // CameraHits
#include "wire/types.hpp"

namespace shadow::oracle {

struct DepthAgreement {
  size_t texels = 0;
  size_t agree = 0;        // |engine - reference| <= tolerance (empty texels hold 1.0 on both)
  size_t engine_only = 0;  // engine drew a caster where the reference has none
  size_t oracle_only = 0;  // reference has a caster the engine left empty
  double max_error = 0.0;  // over all texels
  double max_error_both_covered = 0.0;  // over texels both sides cover (no silhouette misses)
  size_t worst = 0;                     // index of the texel with max_error
  double fraction() const { return texels ? static_cast<double>(agree) / texels : 0.0; }
  std::string summary() const;
};

// Empty texels are 1.0 in both; a texel is "covered" when its depth is below 1.
DepthAgreement compare_depth(std::span<const float> engine, std::span<const double> reference,
                             double tolerance);

struct VisibilityError {
  size_t pixels = 0;
  size_t both_valid = 0;     // finite in both
  size_t nan_mismatch = 0;   // NaN in exactly one of the two
  size_t misclassified = 0;  // |v - v_ref| > 0.5 among both_valid
  size_t first_misclassified = static_cast<size_t>(-1);
  size_t first_nan_mismatch = static_cast<size_t>(-1);
  double mae = 0.0;  // mean |v - v_ref| over both_valid
  double rmse = 0.0;
  double penumbra_mae = 0.0;  // over 0.02 < v_ref < 0.98 (soft references only)
  size_t penumbra_pixels = 0;
  double misclassified_rate() const {
    return both_valid ? static_cast<double>(misclassified) / both_valid : 0.0;
  }
  std::string summary() const;
};

VisibilityError compare_visibility(std::span<const float> engine, std::span<const float> reference);

// The same errors split by each pixel's distance from the eye, since shadow-map techniques that
// redistribute texels (PSM) trade accuracy near the viewer for accuracy far away.
struct DistanceBand {
  double from = 0.0, to = 0.0;  // [from, to) metres from the eye
  VisibilityError error;
  std::string label() const;  // e.g. "<10 m", "10-50 m", ">=50 m"
};

// `distance` holds one eye distance per pixel (NaN where the camera sees nothing); `edges` are the
// inner band limits in increasing order, so {10, 50} gives [0, 10), [10, 50) and [50, inf).
std::vector<DistanceBand> compare_visibility_by_distance(std::span<const float> engine,
                                                         std::span<const float> reference,
                                                         std::span<const double> distance,
                                                         std::span<const double> edges);

// What a camera view shows, per pixel in row order, for telling a shadow edge a map can misplace
// from one the geometry makes (boundary_share).
struct ViewSurface {
  std::vector<glm::dvec3> position;  // world; NaN where nothing is seen
  std::vector<glm::dvec3> normal;    // unit, facing the camera
  // The seen side receives shadows and the light reaches it as the hard test lights it: inside a
  // spot's cone, facing the light (else it is in its own, attached shadow).
  std::vector<uint8_t> lit;
  glm::dvec3 eye{0.0};
  double pixel = 0;  // a pixel's extent per unit distance: 2 tan(fov / 2) / height
};
// The camera's view of a scene as `hits` saw it, lit by `light`.
ViewSurface view_surface(const CameraHits& hits, const Scene& scene, const Camera& camera,
                         const Light& light);

// The share of the pixels seen (finite visibility) on a shadow edge a map can misplace: whose
// visibility differs by more than 0.5 from a 4-neighbour's on the same lit surface. Both are lit
// (ViewSurface::lit), their normals within ~25 degrees (dot > 0.9), and the neighbour no farther
// off than 3 times the step one pixel makes on the first's plane at its distance and slope (the
// cosine of its view angle taken at least 0.05). Elsewhere the change is the geometry's: an
// attached shadow, a spot's rim, a silhouette or a crease, which no map moves. With the
// misclassified rate it separates how many edges a view has from how well a map resolves them
// (the quality goals' calibration).
double boundary_share(std::span<const float> visibility, size_t width, size_t height,
                      const ViewSurface& surface);

// The same count per cell of a columns x rows grid of equal cells, in row order: cell (c, r)
// holds the pixels x in [c width / columns, (c + 1) width / columns), likewise y.
struct CellBoundary {
  size_t seen = 0, boundary = 0;
};
std::vector<CellBoundary> boundary_cells(std::span<const float> visibility, size_t width,
                                         size_t height, size_t columns, size_t rows,
                                         const ViewSurface& surface);
// Per pixel, its cell's boundary share (0 where the cell sees nothing): where a view's shadow
// edges lie, at the grid's resolution.
std::vector<float> local_boundary_share(std::span<const float> visibility, size_t width,
                                        size_t height, size_t columns, size_t rows,
                                        const ViewSurface& surface);

// The hard test's expected misclassified rate from edge sampling alone: the mean, over the pixels
// seen in both, of |hard - bilinear 2x2 PCF| of the same map. A shadow edge between two texel
// centres that disagree lies anywhere between them, so a point is on its wrong side with the
// bilinear weight of the other texel. Blind to every other error: bias, acne, grazing receivers,
// casters missing from the map; measured well above it, the error is one of those.
double edge_sampling_estimate(std::span<const float> hard, std::span<const float> bilinear);

// The bands the street and forest are reported in (eye at 1.7 m, near 0.1, far 2000).
inline constexpr double kStandardDistanceEdges[] = {10.0, 50.0};

}  // namespace shadow::oracle
