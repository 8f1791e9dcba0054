#include "engine/passes/half_pack.hpp"

namespace shadow {

const cl::Buffer& HalfPackPass::run(const cl::Buffer& src, uint32_t first, uint32_t count,
                                    Timeline& timeline) {
  runtime_.ensure(packed_, size_t{count} * sizeof(uint16_t) + 2);
  if (count == 0) return packed_;
  cl_kernel k = kernels_.kernel("half.cl", "pack_half");
  cl::set_args(k, src, first, count, packed_);
  timeline.add("readback.half", runtime_.launch(k, (size_t{count} + kChunk - 1) / kChunk));
  return packed_;
}

}  // namespace shadow
