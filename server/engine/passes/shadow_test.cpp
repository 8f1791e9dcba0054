#include "engine/passes/shadow_test.hpp"

#include "engine/passes/light_args.hpp"
#include "engine/passes/pcf.hpp"

#include <cmath>

namespace shadow {

const cl::Buffer& ShadowTestPass::run(const GBuffer& g, uint32_t pixels, const cl::Buffer& map,
                                      const ViewSetup& light_view, const Light& light,
                                      const ShadowMapSettings& settings, Timeline& timeline) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  const cl::Buffer& visibility = visibility_;
  // PCF's kernel with one nearest texel: its set-up vectorizes (docs/benchmarks.md). The tap
  // pattern is not read; width only seeds Poisson rotation.
  runtime_.ensure(no_taps_, 2 * sizeof(float));
  cl_kernel k = kernels_.kernel("pcf.cl", "pcf", faces_option(light_view));
  cl::set_args(k, g.position, g.normal, pixels, 1u, shadow_lookup(light_view, light, settings), map,
               faces_args(light_view.faces), PcfParams::kNearestMode, no_taps_, 0u, 0.0f, 0,
               visibility);
  timeline.add("visibility.shadow_test", runtime_.launch(k, (pixels + 63) / 64));
  return visibility;
}

}  // namespace shadow
