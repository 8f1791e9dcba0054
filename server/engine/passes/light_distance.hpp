// The distance from a point light to its nearest caster triangle (kernels/light_distance.cl),
// which bounds the near planes of the light's cube faces (engine/light/cube_fit.hpp).
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/device_types.hpp"
#include "engine/passes/scene_buffers.hpp"

namespace shadow {

class LightDistancePass {
 public:
  LightDistancePass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // A lower bound (>= 0) of the distance from `point` to every triangle of `draws` (only
  // their to_world is read); +infinity without triangles. Waits for the device.
  double run(const SceneBuffers& scene, const std::vector<DrawItem>& draws, const glm::vec3& point,
             Timeline& timeline);
  void warm_up() { kernel(); }

 private:
  // min_triangle_distance: a work-group per chunk of triangles (pixel_shape.hpp's chunk_group).
  cl_kernel kernel();
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer draws_, partial_;
  std::vector<float> mins_;
};

}  // namespace shadow
