// The camera view (kernels/gbuffer.cl): world position and normal of the surface at each pixel.
#pragma once

#include "engine/light/light_space.hpp"
#include "engine/passes/pixel_shape.hpp"
#include "engine/passes/rasterizer.hpp"

namespace shadow {

struct GBuffer {
  cl::Buffer position;  // 3 floats per pixel, NaN where the camera sees nothing
  cl::Buffer normal;  // float4 per pixel: unit normal facing the camera, w = 0 no shadows received,
                      // 1 depth test, 2 + k blur receiver class k (kernels/gbuffer.cl)
  // The camera's: the primitive id per pixel and the draws that number them (lookups into the
  // shadow atlas find each pixel's UV from them); null for other views.
  const cl::Buffer* ids = nullptr;
  const cl::Buffer* draws = nullptr;
  uint32_t draw_count = 0;
};

// gbuffer.cl on `runtime`'s device profile: strips of 64 pixels (PIXEL_CHUNK) or a work-item per
// pixel (engine/passes/pixel_shape.hpp).
inline PixelShape gbuffer_shape(const cl::Runtime& runtime) {
  return pixel_shape(runtime, 64);
}

class GBufferPass {
 public:
  GBufferPass(const cl::Runtime& runtime, cl::Kernels& kernels, Rasterizer& rasterizer)
      : runtime_(runtime), kernels_(kernels), rasterizer_(rasterizer) {}

  // The buffers stay valid until the next run. While the step cache keeps, the resolve runs
  // again only when the raster pass did or the camera's rays changed.
  const GBuffer& run(const Scene& scene, const SceneBuffers& buffers, const Camera& camera,
                     const ViewSetup& view, Timeline& timeline);
  void warm_up() {
    kernels_.kernel("gbuffer.cl", "resolve_gbuffer", gbuffer_shape(runtime_).options);
  }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  Rasterizer& rasterizer_;
  GBuffer buffers_;
};

}  // namespace shadow
