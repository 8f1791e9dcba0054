#include "engine/passes/shadow_test.hpp"

#include "engine/passes/light_args.hpp"

#include <cmath>

namespace shadow {

const cl::Buffer& ShadowTestPass::run(const GBuffer& g, uint32_t pixels, const cl::Buffer& map,
                                      const ViewSetup& light_view, const Light& light,
                                      const ShadowMapSettings& settings, Timeline& timeline) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  const cl::Buffer& visibility = visibility_;
  cl_kernel k = kernels_.kernel("shadow_test.cl", "shadow_test", faces_option(light_view));
  cl::set_args(k, g.position, g.normal, pixels, shadow_lookup(light_view, light, settings), map,
               faces_args(light_view.faces), visibility);
  timeline.add("visibility.shadow_test", runtime_.launch(k, (pixels + 63) / 64));
  return visibility;
}

}  // namespace shadow
