#include "engine/passes/shadow_test.hpp"

#include "engine/passes/pcf.hpp"

#include <cmath>

namespace shadow {

const cl::Buffer& ShadowTestPass::run(const GBuffer& g, uint32_t pixels,
                                      const std::vector<LightMap>& maps, const Light& light,
                                      const ShadowMapSettings& settings, Timeline& timeline) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  const cl::Buffer& visibility = visibility_;
  // PCF's kernel with one nearest texel: its set-up vectorizes (docs/benchmarks.md). The tap
  // pattern is not read; width only seeds Poisson rotation.
  runtime_.ensure(no_taps_, 2 * sizeof(float));
  const MapLookup m = map_lookup(maps, light, settings);
  cl_kernel k = kernels_.kernel("pcf.cl", "pcf", m.option);
  cl::set_args(k, g.position, g.normal, pixels, 1u, m.lookup, m.faces, m.cube, *m.maps[0],
               *m.maps[1], *m.maps[2], *m.maps[3], *m.maps[4], *m.maps[5], PcfParams::kNearestMode,
               no_taps_, 0u, 0.0f, 0, visibility);
  timeline.add("visibility.shadow_test", runtime_.launch(k, (pixels + 63) / 64));
  return visibility;
}

}  // namespace shadow
