// Percentage-closer soft shadows (kernels/pcss.cl): blocker search in linear light depth,
// penumbra estimate, variable-radius Poisson PCF. Directional lights (Light::size = angular
// diameter in degrees) and spot lights (Light::size = radius).
#pragma once

#include "engine/light/light_space.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/pixel_shape.hpp"
#include "engine/passes/summed_area.hpp"
#include "engine/run/scene_buffers.hpp"

namespace shadow {

// How the kernel turns the map's NDC z into linear light depth d and lengths into texels.
struct PcssGeometry {
  bool perspective = false;  // spot: z = alpha + beta / d; directional: z = alpha + beta * d
  float alpha = 0.0f, beta = 1.0f;
  float size = 0.0f;      // spot: radius; directional: tan(angular diameter / 2)
  glm::vec2 scale{0.0f};  // texels per unit of x / d (spot) or world unit (directional), u and v
};
PcssGeometry pcss_geometry(const ViewSetup& light_view, const Light& light, uint32_t map_size);

// pcss.cl's kernels on `runtime`'s device profile: strips of 64 pixels or texels (PIXEL_CHUNK) or
// a work-item per pixel (engine/passes/pixel_shape.hpp).
inline PixelShape pcss_shape(const cl::Runtime& runtime) {
  return pixel_shape(runtime, 64);
}

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
  // FILTER_ATLAS_SAT / FILTER_ATLAS_MIP, once per light: PCSS's blocker search and penumbra at
  // every texel of the atlas' G-buffer (`texels`, rows of `width`), into `half_width`.
  void penumbra(const GBuffer& atlas_view, uint32_t texels, uint32_t width, const cl::Buffer& map,
                const ViewSetup& light_view, const Light& light, const ShadowMapSettings& settings,
                const PcssSettings& params, cl::Buffer& half_width, Timeline& timeline);
  // What soften() reads besides the atlas' G-buffer: the penumbra, the hard atlas (`level0`) and
  // with atlas_sat its SAT (`sat`, two channels: visibility and coverage of the surface texels),
  // and the axes and chart of each atlas texel (AtlasPass::texel_axes, texel_charts). The filters
  // keep to one chart: soften() makes the SAT of the charts' moments, or the mips with their charts
  // (`mips`, the ordinary chain, is not read: it mixes charts).
  struct AtlasPrefiltered {
    const cl::Buffer* half_width = nullptr;  // penumbra()'s result
    const SummedAreaTable* sat = nullptr;
    const cl::Buffer* level0 = nullptr;
    const MipChain* mips = nullptr;
    const cl::Buffer* texel_axes = nullptr;
    const cl::Buffer* texel_charts = nullptr;
    uint32_t width = 0, height = 0;  // the atlas
    uint32_t tile = 0;               // its largest tile: the chart chain's last level spans it
    // Each texel's tile (AtlasPass::tile_cells): per cell of `cell` texels, x, y, size, 1.
    const cl::Buffer* cells = nullptr;
    uint32_t cell = 0;
  };
  // The penumbra's footprint in the atlas (seed 004's l_lod, eq. 4-5, as an ellipse) at every
  // texel of the atlas' G-buffer whose `half_width` (penumbra()'s) is positive: three floats a
  // texel (xx, yy, xy) with the ellipse {p : p^T S^-1 p <= 1} in atlas texels, the image of the
  // light's disk of that radius (at least half a map texel) on the surface; NaN elsewhere.
  // `texel_axes`: AtlasPass::texel_axes. Valid until the next call.
  const cl::Buffer& footprint(const GBuffer& atlas_view, const cl::Buffer& texel_axes,
                              const cl::Buffer& half_width, uint32_t texels,
                              const ViewSetup& light_view, const Light& light,
                              const ShadowMapSettings& settings, Timeline& timeline);
  // Then, still once per light: the soft visibility at every atlas texel, the prefiltered atlas
  // read over the penumbra's footprint there within the texel's chart, into `soft` (a word
  // per texel: the visibility as unorm16 and the texel's chart, which run_atlas keeps to; 0
  // where no surface is).
  void soften(const GBuffer& atlas_view, const ViewSetup& light_view, const Light& light,
              const ShadowMapSettings& settings, const AtlasPrefiltered& atlas, cl::Buffer& soft,
              Timeline& timeline);
  // Per camera frame: the soft atlas at each pixel's UV, instead of PCSS. `gbuffer` must be the
  // camera's.
  struct AtlasInputs {
    const SceneBuffers* scene = nullptr;
    const cl::Buffer* uvs = nullptr;    // the scene's UVs in vertex order
    const cl::Buffer* tiles = nullptr;  // uint4 per instance: x, y, size, 1 if it has a tile
    const cl::Buffer* soft = nullptr;   // soften()'s result
    uint32_t width = 0;                 // the atlas'
  };
  const cl::Buffer& run_atlas(const GBuffer& gbuffer, uint32_t pixels, const Light& light,
                              const AtlasInputs& atlas, Timeline& timeline);
  void warm_up();

 private:
  static constexpr uint32_t kAtlasTexelChunk = 256;  // TEXEL_CHUNK in atlas.cl
  // pcss.cl's and atlas.cl's kernels in the device profile's shape, and launches over `count`
  // pixels or texels in it.
  cl_kernel pcss_kernel(const char* name);
  cl_kernel atlas_kernel(const char* name);
  cl::Events launch_pcss(cl_kernel kernel, uint32_t count) const;
  cl::Events launch_texels(cl_kernel kernel, uint32_t count) const;
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer visibility_, taps_, levels_, no_doubles_, footprint_;
  // The atlas filters' chart-aware prefilters: the chart moments (and which texels the attached-
  // shadow rule darkens) and their SAT (atlas_sat), the mip chain with each texel's chart
  // (atlas_mip).
  cl::Buffer chart_moments_, chart_chain_;
  SummedAreaPass chart_sat_{runtime_, kernels_};
  std::vector<glm::vec2> pattern_;
  std::vector<glm::uvec4> level_table_;  // a member: the write is asynchronous
  // Uploads the tap patterns when they changed.
  void set_patterns(const PcssSettings& params, const char* pass, Timeline& timeline);
  uint32_t blockers_ = 0, filters_ = 0;  // the patterns now in taps_
};

}  // namespace shadow
