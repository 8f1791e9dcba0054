// The soft shadow atlas (FILTER_ATLAS_SAT, FILTER_ATLAS_MIP; kernels/atlas_soften.cl): once per
// light, PCSS's penumbra at every atlas texel (PcssPass::penumbra) read over the prefiltered hard
// atlas within each texel's chart; then per camera frame one lookup per pixel instead of PCSS.
#pragma once

#include <vector>

#include "engine/light/light_space.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/scene_buffers.hpp"
#include "engine/passes/summed_area.hpp"

namespace shadow {

class AtlasSoftenPass {
 public:
  AtlasSoftenPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // What soften() reads besides the atlas' G-buffer: the penumbra, the hard atlas (`level0`) and
  // with atlas_sat its SAT (`sat`, two channels: visibility and coverage of the surface texels),
  // and the axes and chart of each atlas texel (AtlasPass::texel_axes, texel_charts). The filters
  // keep to one chart: soften() makes the SAT of the charts' moments, or the mips with their charts
  // (`mips`, the ordinary chain, is not read: it mixes charts).
  struct AtlasPrefiltered {
    const cl::Buffer* half_width = nullptr;  // PcssPass::penumbra's result
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
  // texel of the atlas' G-buffer whose `half_width` (PcssPass::penumbra's) is positive: three
  // floats a texel (xx, yy, xy) with the ellipse {p : p^T S^-1 p <= 1} in atlas texels, the image
  // of the light's disk of that radius (at least half a map texel) on the surface; NaN elsewhere.
  // `texel_axes`: AtlasPass::texel_axes. Valid until the next call.
  const cl::Buffer& footprint(const GBuffer& atlas_view, const cl::Buffer& texel_axes,
                              const cl::Buffer& half_width, uint32_t texels,
                              const ViewSetup& light_view, const Light& light,
                              const ShadowMapSettings& settings, Timeline& timeline);
  // Then, still once per light: the soft visibility at every atlas texel, the prefiltered atlas
  // read over the penumbra's footprint there within the texel's chart, into `soft` (a word
  // per texel: the visibility as unorm16 and the texel's chart, which lookup keeps to; 0
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
  const cl::Buffer& lookup(const GBuffer& gbuffer, uint32_t pixels, const Light& light,
                           const AtlasInputs& atlas, Timeline& timeline);
  void warm_up();

 private:
  static constexpr uint32_t kSoftChunk = 64;    // PIXEL_CHUNK in atlas_soften.cl
  static constexpr uint32_t kChartChunk = 256;  // TEXEL_CHUNK there
  // atlas_soften.cl's kernels in the device profile's shape, and launches over `count` pixels or
  // texels in it: the soft kernels' strips, the chart kernels'.
  cl_kernel kernel(const char* name);
  cl::Events launch_soft(cl_kernel kernel, uint32_t count) const;
  cl::Events launch_texels(cl_kernel kernel, uint32_t count) const;
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer visibility_, levels_, no_doubles_, footprint_;
  // The chart-aware prefilters: the chart moments (and which texels the attached-shadow rule
  // darkens) and their SAT (atlas_sat), the mip chain with each texel's chart (atlas_mip).
  cl::Buffer chart_moments_, chart_chain_;
  SummedAreaPass chart_sat_{runtime_, kernels_};
  std::vector<glm::uvec4> level_table_;  // a member: the write is asynchronous
};

}  // namespace shadow
