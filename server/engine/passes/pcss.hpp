// Percentage-closer soft shadows (kernels/pcss.cl): blocker search in linear light depth,
// penumbra estimate, variable-radius Poisson PCF. Directional lights (Light::size = angular
// diameter in degrees) and spot lights (Light::size = radius).
#pragma once

#include "engine/light_space.hpp"
#include "engine/passes/gbuffer.hpp"

namespace shadow {

// How the kernel turns the map's NDC z into linear light depth d and lengths into texels.
struct PcssGeometry {
  bool perspective = false;  // spot: z = alpha + beta / d; directional: z = alpha + beta * d
  float alpha = 0.0f, beta = 1.0f;
  float size = 0.0f;      // spot: radius; directional: tan(angular diameter / 2)
  glm::vec2 scale{0.0f};  // texels per unit of x / d (spot) or world unit (directional), u and v
};
PcssGeometry pcss_geometry(const ViewSetup& light_view, const Light& light, uint32_t map_size);

class PcssPass {
 public:
  static constexpr uint32_t kMaxTaps = 64;        // as MAX_TAPS in pcss.cl
  static constexpr float kMaxSearchTexels = 128;  // blocker-search radius cap

  PcssPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // Visibility per camera pixel (1 lit .. 0 shadowed, NaN where nothing is seen); valid until
  // the next run. Settings are validated upstream.
  const cl::Buffer& run(const GBuffer& gbuffer, uint32_t pixels, uint32_t width,
                        const cl::Buffer& map, const ViewSetup& light_view, const Light& light,
                        const ShadowMapSettings& settings, const PcssSettings& params,
                        Timeline& timeline);
  void warm_up() { kernels_.kernel("pcss.cl", "pcss"); }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer visibility_, taps_;
  std::vector<glm::vec2> pattern_;
  uint32_t blockers_ = 0, filters_ = 0;  // the patterns now in taps_
};

}  // namespace shadow
