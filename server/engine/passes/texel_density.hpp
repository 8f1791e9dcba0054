// Perspective aliasing per camera pixel (kernels/texel_density.cl): the size in pixels of one
// shadow-map texel's footprint on the visible surface.
#pragma once

#include "engine/light/light_space.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/pixel_shape.hpp"

namespace shadow {

// texel_density.cl on `runtime`'s device profile: strips of 64 pixels (PIXEL_CHUNK) or a
// work-item per pixel (engine/passes/pixel_shape.hpp).
inline PixelShape texel_density_shape(const cl::Runtime& runtime) {
  return pixel_shape(runtime, 64);
}

class TexelDensityPass {
 public:
  TexelDensityPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // One float per pixel: the longest axis of a texel's footprint in pixels; NaN where the camera
  // sees nothing or the point is outside the map, +inf where the light grazes the surface.
  // A cube's pixels each in their face, in one launch. The buffer stays valid until the next run.
  const cl::Buffer& run(const GBuffer& gbuffer, const Camera& camera, const ViewSetup& camera_view,
                        const std::vector<LightMap>& maps, uint32_t map_size, Timeline& timeline);
  void warm_up() {
    for (const char* options : {"", "-DCUBE_FACES"})
      kernels_.kernel("texel_density.cl", "texel_density",
                      texel_density_shape(runtime_).with(options));
  }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer density_;
};

}  // namespace shadow
