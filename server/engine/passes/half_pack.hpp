// float32 device values -> IEEE binary16 (kernels/half_pack.cl), for requests whose float products
// travel as PIXEL_FORMAT_FLOAT16.
#pragma once

#include <cstdint>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/runtime.hpp"
#include "engine/cl/timeline.hpp"

namespace shadow {

class HalfPackPass {
 public:
  static constexpr uint32_t kChunk = 4096;  // HALF_CHUNK in half_pack.cl

  HalfPackPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // `count` floats of `src` from float `first` on, as halves; valid until the next run.
  const cl::Buffer& run(const cl::Buffer& src, uint32_t first, uint32_t count, Timeline& timeline);
  void warm_up() { kernel(); }

 private:
  cl_kernel kernel();  // pack_half in the device profile's shape (pixel_shape.hpp)
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer packed_;
};

}  // namespace shadow
