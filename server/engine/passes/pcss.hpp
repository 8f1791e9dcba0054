// Percentage-closer soft shadows (kernels/pcss.cl): blocker search in linear light depth,
// penumbra estimate, variable-radius Poisson PCF. Directional lights (Light::size = angular
// diameter in degrees) and spot lights (Light::size = radius).
#pragma once

#include "engine/light/light_space.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/pixel_shape.hpp"
#include "engine/passes/virtual_pages.hpp"

namespace shadow {

// How the kernel turns the map's NDC z into linear light depth d and lengths into texels.
struct PcssGeometry {
  bool perspective = false;  // spot: z = alpha + beta / d; directional: z = alpha + beta * d
  float alpha = 0.0f, beta = 1.0f;
  float size = 0.0f;      // spot: radius; directional: tan(angular diameter / 2)
  glm::vec2 scale{0.0f};  // texels per unit of x / d (spot) or world unit (directional), u and v
};
PcssGeometry pcss_geometry(const ViewSetup& light_view, const Light& light, uint32_t map_size);

// What virtual_mark (kernels/virtual_pages.cl) needs to bound a pixel's blocker search on a
// virtual map `layout` of `light` (a sun or a spot light): the light's size (tan of half the
// sun's angle, or the spot's radius), the levels' near depth and level 0's texels per unit of
// the search (world units, or x / d for a spot light); w unused.
glm::vec4 pcss_search_bound(const VirtualLevels& layout, const Light& light);

// pcss.cl's kernels on `runtime`'s device profile: strips of 64 pixels or texels (PIXEL_CHUNK) or
// a work-item per pixel (engine/passes/pixel_shape.hpp).
inline PixelShape pcss_shape(const cl::Runtime& runtime) {
  return pixel_shape(runtime, 64);
}

class PcssPass {
 public:
  static constexpr uint32_t kMaxTaps = 64;        // as MAX_TAPS in pcss.cl
  static constexpr float kMaxSearchTexels = 128;  // blocker-search radius cap
  // A virtual map's: within the kMaxSoftReach texels around a pixel that marking gives pages.
  static constexpr float kMaxVirtualSearch = float(kMaxSoftReach - 1);

  PcssPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // Visibility per camera pixel (1 lit .. 0 shadowed, NaN where nothing is seen); valid until
  // the next run. Settings are validated upstream.
  // `pages`: a virtual map (issue 53), whose pool is `map` and whose levels each pixel reads
  // (marking chose them so that the search stays within kMaxVirtualSearch texels).
  const cl::Buffer& run(const GBuffer& gbuffer, uint32_t pixels, uint32_t width,
                        const cl::Buffer& map, const ViewSetup& light_view, const Light& light,
                        const ShadowMapSettings& settings, const PcssSettings& params,
                        Timeline& timeline, const VirtualMap* pages = nullptr);
  // FILTER_ATLAS_SAT / FILTER_ATLAS_MIP, once per light: PCSS's blocker search and penumbra at
  // every texel of the atlas' G-buffer (`texels`, rows of `width`), into `half_width`.
  void penumbra(const GBuffer& atlas_view, uint32_t texels, uint32_t width, const cl::Buffer& map,
                const ViewSetup& light_view, const Light& light, const ShadowMapSettings& settings,
                const PcssSettings& params, cl::Buffer& half_width, Timeline& timeline);
  void warm_up();

 private:
  // pcss.cl's kernels in the device profile's shape, and launches over `count` pixels or texels
  // in it.
  cl_kernel pcss_kernel(const char* name, bool paged = false);
  cl::Events launch_pcss(cl_kernel kernel, uint32_t count) const;
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer visibility_, taps_, level_geometry_;
  std::vector<glm::vec4> geometry_table_;  // per virtual level: alpha, beta, scale (written async)
  std::vector<glm::vec2> pattern_;
  // Uploads the tap patterns when they changed.
  void set_patterns(const PcssSettings& params, const char* pass, Timeline& timeline);
  uint32_t blockers_ = 0, filters_ = 0;  // the patterns now in taps_
};

}  // namespace shadow
