#include "engine/passes/shadow_test.hpp"

#include "engine/passes/pcf.hpp"

#include <cmath>

namespace shadow {

const cl::Buffer& ShadowTestPass::run(const GBuffer& g, uint32_t pixels,
                                      const std::vector<LightMap>& maps, const Light& light,
                                      const ShadowMapSettings& settings, Timeline& timeline,
                                      const ViewDepthOut* depth) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  const cl::Buffer& visibility = visibility_;
  // PCF's kernel with one nearest texel: its set-up vectorizes (docs/benchmarks.md). The tap
  // pattern is not read; width only seeds Poisson rotation.
  runtime_.ensure(no_taps_, 2 * sizeof(float));
  timeline.add("visibility.shadow_test",
               launch_pcf(runtime_, kernels_, g, pixels, 1u, maps, light, settings,
                          PcfParams::kNearestMode, no_taps_, 0u, 0.0f, false, visibility, depth));
  return visibility;
}

}  // namespace shadow
