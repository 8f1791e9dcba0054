// Ray-traced ground truth for the shadow engine, built on Embree and independent of OpenCL.
// Embree only finds which triangle a ray meets; every reported position and depth is then
// recomputed in double precision from that triangle's world-space plane, so the reference is
// limited by geometry, not by Embree's float arithmetic.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "wire/types.hpp"

namespace shadow::oracle {

struct DepthOptions {
  // A rasterizer with homogeneous clipping draws only points with clip w > 0. The default keeps
  // the pure projective rule (every point whose NDC z lies in [0, 1] counts) that the issue
  // states; set this to match a map whose negative-w half must not count.
  bool require_positive_w = false;
};

struct VisibilityOptions {
  // Shadow-ray origins move this far along the normal, times the scene's bounding-box diagonal,
  // and never less than RayOracle::min_ray_offset() (Embree intersects in float). An offset is a
  // bias of the reference toward lit: it lifts a grazing receiver by offset / tan(elevation).
  // At 1e-4 the reference itself misclassified up to 0.75% of a street's pixels (a band along
  // every long shadow edge); 1e-5 still moved the street by 0.04 points; 1e-6 and 1e-7 agree.
  double offset_scale = 1e-6;
  // Only the side the normal points to is lit: a point whose normal faces away from the light
  // is in its own shadow, even on an open surface (VISIBILITY's definition: the side the camera
  // sees). False: either side, the one facing the light (the normal is flipped to it).
  bool seen_side = false;
};

// What the camera's primary ray through each pixel centre meets, row 0 at the top.
struct CameraHits {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<glm::dvec3> position;  // world; NaN where the ray meets nothing in [near, far]
  std::vector<glm::dvec3> normal;    // geometric, unit, facing the camera; NaN where nothing
  std::vector<int32_t> instance;     // index into Scene::instances; -1 where nothing
  std::vector<int32_t> triangle;     // triangle index within the instance's mesh; -1 where nothing

  size_t size() const { return position.size(); }
  bool hit(size_t i) const { return instance[i] >= 0; }
};

// One Embree scene per shadow::Scene, reusable across many queries. Instances are flattened
// into world-space triangles; only instances with casts_shadows occlude light or fill a map.
class RayOracle {
 public:
  explicit RayOracle(const Scene& scene);
  ~RayOracle();
  RayOracle(const RayOracle&) = delete;
  RayOracle& operator=(const RayOracle&) = delete;

  // Expected NDC z of the nearest shadow caster on the line through NDC point (x, y): every hit
  // along the whole world line is collected and the smallest NDC z in [0, 1] wins; 1.0 if none.
  double texel_depth(const glm::dmat4& world_to_ndc, const glm::dmat4& ndc_to_world, double x,
                     double y, const DepthOptions& options = {}) const;

  // texel_depth at every texel centre ((i+0.5)/size, (j+0.5)/size) of a size x size map,
  // row-major with row 0 at the top.
  std::vector<double> shadow_map_depth(const glm::dmat4& world_to_ndc, uint32_t size,
                                       const DepthOptions& options = {}) const;

  // 1 = lit, 0 = shadowed, one hard shadow ray per point. The normal is flipped to face the light
  // before the origin is offset, so a back-facing point of a closed caster reads as shadowed.
  // Points outside a spot light's cone (or behind it) are 0; NaN points stay NaN. `receives`
  // (optional, one per point) marks points whose surface ignores occluders: those are lit if the
  // light reaches their direction at all.
  std::vector<float> hard_visibility(const Light& light, std::span<const glm::dvec3> points,
                                     std::span<const glm::dvec3> normals,
                                     std::span<const uint8_t> receives = {},
                                     const VisibilityOptions& options = {}) const;

  // Primary rays through every pixel centre, clipped to view depth [near, far] as a rasterizer
  // clips; all instances are visible whatever their shadow flags.
  CameraHits cast_camera(const Camera& camera) const;

  // Lit/shadowed for the surfaces the camera sees (NaN where it sees nothing), with
  // non-receiving instances reading as unshadowed. Always options.seen_side: the camera's side.
  std::vector<float> camera_visibility(const Camera& camera, const Light& light,
                                       const VisibilityOptions& options = {}) const;

  // Whether a caster lies on the segment origin + t * direction, 0 <= t < max_distance
  // (direction unit length; infinity for a ray). The building block of area-light sampling.
  bool occluded(const glm::dvec3& origin, const glm::dvec3& direction, double max_distance) const;

  double scene_diagonal() const;
  // The smallest shadow-ray offset the oracle uses: a few float ulps of the scene's largest
  // coordinate, where Embree's float intersection could meet the receiver itself.
  double min_ray_offset() const;
  const Scene& scene() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One-shot conveniences over RayOracle (each builds the Embree scene anew).
std::vector<double> shadow_map_depth(const Scene& scene, const glm::mat4& world_to_ndc,
                                     uint32_t size, const DepthOptions& options = {});
std::vector<float> hard_visibility(const Scene& scene, const Light& light,
                                   std::span<const glm::dvec3> points,
                                   std::span<const glm::dvec3> normals,
                                   const VisibilityOptions& options = {});
CameraHits cast_camera(const Scene& scene, const Camera& camera);

}  // namespace shadow::oracle
