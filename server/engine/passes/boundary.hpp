// The share of a camera view's seen pixels on a shadow boundary (kernels/reduce.cl,
// boundary_partials): whose visibility differs by more than 0.5 from a seen 4-neighbour's. A
// quality goal's probe measures it on a small uniform map to scale its predicted error to the
// view's shadow edges (engine/quality_pick.hpp).
#pragma once

#include "engine/cl/program_cache.hpp"
#include "engine/timeline.hpp"

namespace shadow {

class BoundaryPass {
 public:
  BoundaryPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // `visibility` holds width x height floats (NaN where nothing is seen); 0 when none is seen.
  // Reads one pair of counts per row back, so it waits for the visibility.
  double run(const cl::Buffer& visibility, uint32_t width, uint32_t height, Timeline& timeline);
  void warm_up() { kernels_.kernel("reduce.cl", "boundary_partials"); }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer partials_;
};

}  // namespace shadow
