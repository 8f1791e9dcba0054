// A camera view's shadow boundaries (kernels/reduce.cl, boundary_cells): its seen pixels whose
// visibility differs by more than 0.5 from a seen 4-neighbour's, counted per cell of the quality
// goals' sample grid. A goal's probe measures them on a small uniform map: the share scales its
// predicted error to the view's shadow edges, and the cells weigh each sample by the edges near
// it (engine/quality_pick.hpp).
#pragma once

#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/timeline.hpp"

namespace shadow {

struct BoundaryCount {
  double share = 0;  // of the seen pixels; 0 when none is seen
  // Per cell of the kSampleColumns x kSampleRows grid (auto_pick.hpp), in row order: its
  // boundary pixels.
  std::vector<uint32_t> cells;
};

class BoundaryPass {
 public:
  BoundaryPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // `visibility` holds width x height floats (NaN where nothing is seen). Reads one pair of
  // counts per cell back, so it waits for the visibility.
  BoundaryCount run(const cl::Buffer& visibility, uint32_t width, uint32_t height,
                    Timeline& timeline);
  void warm_up() { kernels_.kernel("reduce.cl", "boundary_cells"); }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer cells_;
};

}  // namespace shadow
