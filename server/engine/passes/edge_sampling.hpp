// The misclassified share edge sampling alone explains in a camera view: the mean over the seen
// pixels of |hard - bilinear 2x2|, two tests of the same map, in one launch of pcf.cl (PCF_EDGE)
// and one of kernels/edge_sampling.cl (edge_sampling_partials). It needs no reference:
// TECHNIQUE_AUTO tries its candidates with it (auto_pick.hpp, choose_by_trial). shadow-bench's
// oracle::edge_sampling_estimate is the same mean in double precision, from the two tests run
// apart; against the ray-traced error, log(estimate / measured) was -0.02 +- 0.45 over the
// bench's hard cases (docs/bench/results.md).
#pragma once

#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/pcf.hpp"

namespace shadow {

class EdgeSamplingPass {
 public:
  EdgeSamplingPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // The camera view `g` (width x height) against `maps`: the mean, 0 when no pixel is seen.
  // Reads one pair per row back, so it waits for the tests.
  double run(const GBuffer& g, uint32_t width, uint32_t height, const std::vector<LightMap>& maps,
             const Light& light, const ShadowMapSettings& settings, Timeline& timeline);
  // The reduction alone: the mean of `difference` (width x height floats, NaN where unseen) over
  // its seen pixels.
  double mean(const cl::Buffer& difference, uint32_t width, uint32_t height, Timeline& timeline);
  // The per-pixel differences of the last run, valid until the next.
  const cl::Buffer& difference() const { return difference_; }
  void warm_up() {
    for (const char* options : {"", "-DCUBE_FACES"}) warm_pcf(kernels_, options);
    kernels_.kernel("edge_sampling.cl", "edge_sampling_partials");
  }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer difference_, no_taps_, partials_;
};

}  // namespace shadow
