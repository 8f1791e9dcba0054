#include "engine/passes/pcf.hpp"

#include <cmath>
#include <stdexcept>

#include "engine/passes/poisson_disk.hpp"
#include "engine/passes/virtual_pages.hpp"

namespace shadow {

const cl::Buffer& PcfPass::run(const GBuffer& g, uint32_t pixels, uint32_t width,
                               const std::vector<LightMap>& maps, const Light& light,
                               const ShadowMapSettings& settings, const PcfParams& params,
                               Timeline& timeline) {
  const bool poisson = params.mode == PcfParams::Mode::kPoisson;
  if (poisson && (params.taps == 0 || params.taps > kMaxTaps))
    throw std::invalid_argument("pcf: 1..64 taps");  // validated with field paths upstream
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  const uint32_t taps = poisson ? params.taps : 0;
  if (poisson && taps != tap_count_) {
    pattern_ = poisson_disk(taps);  // a member: the write is asynchronous
    runtime_.ensure(taps_, kMaxTaps * sizeof(glm::vec2));
    timeline.add("visibility.pcf",
                 runtime_.write(taps_, pattern_.data(), taps * sizeof(glm::vec2)));
    tap_count_ = taps;
  }
  runtime_.ensure(taps_, kMaxTaps * sizeof(glm::vec2));
  timeline.add("visibility.pcf", launch_pcf(runtime_, kernels_, g, pixels, width, maps, light,
                                            settings, static_cast<int>(params.mode), taps_, taps,
                                            params.radius, params.rotate, visibility_));
  return visibility_;
}

cl::Events launch_pcf(const cl::Runtime& runtime, cl::Kernels& kernels, const GBuffer& g,
                      uint32_t pixels, uint32_t width, const std::vector<LightMap>& maps,
                      const Light& light, const ShadowMapSettings& settings, int mode,
                      const cl::Buffer& taps, uint32_t tap_count, float radius, bool rotate,
                      const cl::Buffer& out, const ViewDepthOut* depth) {
  const MapLookup m = map_lookup(maps, light, settings);
  if (depth && *m.option) throw std::logic_error("pcf: the view depth of a single map only");
  // VIEW_DEPTH keeps the strips on every profile: its partials are one per strip of kPcfStrip
  // pixels (DepthRangePass::read combines them).
  const PixelShape shape = depth ? strip_shape(kPcfStrip) : pcf_shape(runtime);
  cl_kernel k = kernels.kernel("pcf.cl", "pcf", shape.with(depth ? "-DVIEW_DEPTH" : m.option));
  cl::set_args(k, g.position, g.normal, pixels, width, m.lookup, m.faces, m.cube, *m.maps[0],
               *m.maps[1], *m.maps[2], *m.maps[3], *m.maps[4], *m.maps[5], mode, taps, tap_count,
               radius, static_cast<int>(rotate), out);
  if (depth) {  // VIEW_DEPTH's arguments follow `out` (0-based 18)
    cl::set_arg(k, 19, depth->eye);
    cl::set_arg(k, 20, depth->forward);
    cl::set_arg(k, 21, *depth->partials);
  }
  if (m.pages) {  // VIRTUAL's arguments follow `out`
    cl::set_arg(k, 19, m.pages->table);
    cl::set_arg(k, 20, m.pages->level_ndc);
    cl::set_arg(k, 21, m.pages->level_texels);
    cl::set_arg(k, 22, m.pages->pixel_level);
  }
  return runtime.launch(k, shape.work_items(pixels), shape.group);
}

}  // namespace shadow
