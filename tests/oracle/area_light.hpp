// Area-light (soft) visibility: the fraction of the light's disk that a surface point sees,
// estimated with stratified shadow rays until two independent estimates agree within a tolerance.
//
// The light's disk (Light::size):
// - directional: a cone of directions of angular diameter `size` degrees around -direction,
//   sampled uniformly over its tangent-plane disk of radius tan(size / 2) (the "projected disk"
//   PCSS assumes; it differs from uniform solid angle by < 1e-4 for a 5-degree sun);
// - spot: a disk of radius `size` centred on the light, perpendicular to the spot's axis
//   (the lamp's aperture, the light-space plane a PCSS search works in);
// - point: a disk of radius `size` facing the shaded point (a sphere's silhouette, far away).
// Samples below the point's tangent plane count as blocked (the surface hides them). With
// size = 0 every ray goes to the light's centre: the result equals hard visibility.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "oracle/oracle.hpp"

namespace shadow::oracle {

struct AreaLightOptions {
  // Target error of each point's visibility: refine until four standard errors (estimated
  // from strata whose two jittered samples disagree) fit inside it.
  double tolerance = 0.01;
  // The strata grid starts at min_grid^2 strata and doubles its edge up to max_grid (then the
  // point counts as unconverged). 16 keeps a blocked sliver of the disk from hiding between
  // samples (8 missed a 2.3% sliver in the half-plane test).
  uint32_t min_grid = 16;
  uint32_t max_grid = 128;
  // Shadow-ray origins move this far along the normal, as VisibilityOptions::offset_scale.
  double offset_scale = 1e-6;
  uint64_t seed = 1;
  // As VisibilityOptions::seen_side: only the side the normal points to sees the light (each
  // sample below its horizon is blocked); false: the side facing the light's centre.
  bool seen_side = false;
};

struct AreaVisibility {
  std::vector<float> visibility;  // 0..1 per point; NaN where the point is NaN
  size_t unconverged = 0;         // points that hit max_grid without meeting the tolerance
  uint64_t rays = 0;
};

// Points outside a spot light's cone (tested from the light's centre) are 0; points whose
// `receives` entry is 0 ignore occluders (1 if the light reaches their direction at all).
AreaVisibility area_visibility(const RayOracle& oracle, const Light& light,
                               std::span<const glm::dvec3> points,
                               std::span<const glm::dvec3> normals,
                               std::span<const uint8_t> receives = {},
                               const AreaLightOptions& options = {});

// area_visibility for the surfaces the camera sees (NaN where it sees nothing), seen_side.
AreaVisibility camera_area_visibility(const RayOracle& oracle, const Camera& camera,
                                      const Light& light, const AreaLightOptions& options = {});

// Concentric (Shirley-Chiu) map of the unit square onto the unit disk: equal areas, so square
// strata stay equal-area strata of the disk.
glm::dvec2 square_to_disk(glm::dvec2 u);

}  // namespace shadow::oracle
