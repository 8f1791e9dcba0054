// A camera view's shadow edges that a map can misplace (kernels/boundary.cl): its
// seen pixels whose visibility differs by more than 0.5 from a 4-neighbour's on the same lit
// surface, counted per cell of the quality goals' sample grid. Where the lit/dark change is the
// geometry's (an attached shadow, a spot's rim, a silhouette, a crease) no map errs, so those do
// not count. A goal's probe measures them on a small uniform map: the share scales its predicted
// error to the view's shadow edges, and the cells weigh each sample by the edges near it
// (engine/choose/quality_pick.hpp).
#pragma once

#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/passes/gbuffer.hpp"
#include "wire/types.hpp"

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

  // `visibility` holds `camera`'s width x height floats (NaN where nothing is seen), the hard
  // test of `light` over `view`, the camera's G-buffer. Reads one pair of counts per cell back,
  // so it waits for the visibility.
  BoundaryCount run(const cl::Buffer& visibility, const GBuffer& view, const Camera& camera,
                    const Light& light, Timeline& timeline);
  void warm_up() { kernel(); }

 private:
  // boundary_cells in the device profile's shape: a work-item per cell or a
  // work-group (boundary_cells_gpu, issue 42; pixel_shape.hpp's chunk_group); the same counts.
  cl_kernel kernel();
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer cells_;
};

}  // namespace shadow
