// Ping-pong blur of receiver-class planes (kernels/blur.cl, Kozlov GPU Gems 14.4.2): one-hot
// planes from the shadow map's nearest-primitive ids, a separable Gaussian applied back and
// forth between two buffers, and the projection of the blurred plane onto class receivers.
#pragma once

#include <vector>

#include "engine/light/light_space.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/pixel_shape.hpp"
#include "engine/passes/rasterizer.hpp"

namespace shadow {

class BlurPass {
 public:
  static constexpr uint32_t kStrip = 64;  // as STRIP in blur.cl

  BlurPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // 2 * radius + 1 normalized weights exp(-k^2 / (2 sigma^2)), sigma = radius / 2, in double
  // then rounded to float (the kernel's weights).
  static std::vector<float> weights(uint32_t radius);

  // Plane k of size x size floats = 1 where the raster's nearest primitive is an instance of
  // class k, planes 0..planes-1. Needs a raster run with ids. Valid until the next run.
  const cl::Buffer& classify(const RasterOutput& raster, uint32_t draw_count, uint32_t size,
                             uint32_t planes, Timeline& timeline);
  // Blurs `planes` planes of width x height in `data` in place: `passes` times a horizontal
  // then a vertical pass through a scratch buffer.
  void blur(const cl::Buffer& data, uint32_t width, uint32_t height, uint32_t planes,
            uint32_t radius, uint32_t passes, Timeline& timeline);
  // Replaces class receivers' values in `visibility` (the hard test's) with their blurred plane.
  void apply(const GBuffer& gbuffer, uint32_t pixels, const cl::Buffer& blurred,
             const ViewSetup& light_view, const Light& light, uint32_t map_size,
             const cl::Buffer& visibility, Timeline& timeline);

  void warm_up() {
    for (const char* k : {"blur_classes", "blur_rows", "blur_columns", "blur_visibility"})
      kernel(k);
  }

 private:
  // blur.cl's kernel in the device profile's shape: strips of kStrip texels or pixels per
  // work-item, or one (pixel_shape.hpp).
  PixelShape shape() const { return pixel_shape(runtime_, kStrip); }
  cl_kernel kernel(const char* name) { return kernels_.kernel("blur.cl", name, shape().options); }
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer planes_, scratch_, weights_;
  std::vector<float> weight_data_;  // a member: the upload is asynchronous
  uint32_t radius_ = 0;             // the weights now in weights_
};

}  // namespace shadow
