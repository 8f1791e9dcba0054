// The misclassified share edge sampling alone explains in a camera view (kernels/reduce.cl,
// edge_sampling_partials): the mean |hard - bilinear 2x2| over the pixels both tests see, for
// two tests of the same map. It needs no reference: TECHNIQUE_AUTO tries its candidates with it
// (auto_pick.hpp, choose_by_trial). shadow-bench's oracle::edge_sampling_estimate is the same
// mean in double precision; against the ray-traced error, log(estimate / measured) was
// -0.02 +- 0.45 over the bench's hard cases (docs/bench/results.md).
#pragma once

#include "engine/cl/program_cache.hpp"
#include "engine/timeline.hpp"

namespace shadow {

class EdgeSamplingPass {
 public:
  EdgeSamplingPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // `hard` and `filtered` hold width x height floats (NaN where nothing is seen); 0 when no pixel
  // is seen by both. Reads one pair per row back, so it waits for both.
  double run(const cl::Buffer& hard, const cl::Buffer& filtered, uint32_t width, uint32_t height,
             Timeline& timeline);
  void warm_up() { kernels_.kernel("reduce.cl", "edge_sampling_partials"); }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer partials_;
};

}  // namespace shadow
