#include "engine/passes/half_pack.hpp"

#include "engine/passes/pixel_shape.hpp"

namespace shadow {

cl_kernel HalfPackPass::kernel() {
  return kernels_.kernel("half_pack.cl", "pack_half", pixel_shape(runtime_, kChunk).options);
}

const cl::Buffer& HalfPackPass::run(const cl::Buffer& src, uint32_t first, uint32_t count,
                                    Timeline& timeline) {
  runtime_.ensure(packed_, size_t{count} * sizeof(uint16_t) + 2);
  if (count == 0) return packed_;
  cl_kernel k = kernel();
  cl::set_args(k, src, first, count, packed_);
  const PixelShape shape = pixel_shape(runtime_, kChunk);
  timeline.add("readback.half", runtime_.launch(k, shape.work_items(count), shape.group));
  return packed_;
}

}  // namespace shadow
