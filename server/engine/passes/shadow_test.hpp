// The per-pixel hard shadow test: camera surfaces against a shadow map, nearest texel (kernels/
// pcf.cl, mode PCF_NEAREST).
#pragma once

#include "engine/light/light_space.hpp"
#include "engine/passes/depth_range.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/pcf.hpp"

namespace shadow {

class ShadowTestPass {
 public:
  ShadowTestPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // Visibility per camera pixel: 1 lit, 0 shadowed, NaN where the camera sees nothing; a cube's
  // pixels each in their face, in one launch. The buffer stays valid until the next run. With
  // `depth` (a single map only), the view-depth range's partials too, one per kPcfStrip pixels.
  const cl::Buffer& run(const GBuffer& gbuffer, uint32_t pixels, const std::vector<LightMap>& maps,
                        const Light& light, const ShadowMapSettings& settings, Timeline& timeline,
                        const ViewDepthOut* depth = nullptr);
  void warm_up() {
    for (const char* options : {"", "-DCUBE_FACES"})
      warm_pcf(kernels_, pcf_shape(runtime_).with(options));
    warm_pcf(kernels_, "-DVIEW_DEPTH");  // strips on every profile (launch_pcf)
  }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer visibility_, no_taps_;
};

}  // namespace shadow
