#include "engine/passes/pcss.hpp"

#include "engine/passes/light_args.hpp"

#include <cmath>

#include "engine/passes/poisson_disk.hpp"

namespace shadow {

PcssGeometry pcss_geometry(const ViewSetup& light_view, const Light& light, uint32_t map_size) {
  // The light's projection alone (eye space -> texture NDC), probed at two depths.
  const glm::dmat4 proj = light_view.world_to_ndc * glm::inverse(light_view.view);
  const auto z_at = [&](double d) {
    const glm::dvec4 c = proj * glm::dvec4(0, 0, -d, 1);
    return c.z / c.w;
  };
  PcssGeometry g;
  g.perspective = light.type == LightType::kSpot;
  const double z1 = z_at(1.0), z2 = z_at(2.0);
  const double beta = g.perspective ? 2.0 * (z1 - z2) : z2 - z1;
  g.beta = float(beta);
  g.alpha = float(g.perspective ? z1 - beta : z1 - beta);
  // u's gradient in eye-space x, y (per unit of x / d for a spot): the fit may rotate the map
  // about the light's axis, so both components count.
  g.scale = glm::vec2(map_size * std::hypot(proj[0][0], proj[1][0]),
                      map_size * std::hypot(proj[0][1], proj[1][1]));
  g.size = g.perspective ? light.size : float(std::tan(glm::radians(0.5 * light.size)));
  return g;
}

void PcssPass::set_patterns(const PcssSettings& params, const char* pass, Timeline& timeline) {
  runtime_.ensure(taps_, 2 * kMaxTaps * sizeof(glm::vec2));
  if (params.blocker_samples != blockers_ || params.filter_samples != filters_) {
    pattern_.assign(2 * kMaxTaps, glm::vec2(0.0f));  // a member: the write is asynchronous
    const auto b = poisson_disk(params.blocker_samples), f = poisson_disk(params.filter_samples);
    std::copy(b.begin(), b.end(), pattern_.begin());
    std::copy(f.begin(), f.end(), pattern_.begin() + kMaxTaps);
    timeline.add(pass, runtime_.write(taps_, pattern_.data(), pattern_.size() * sizeof(glm::vec2)));
    blockers_ = params.blocker_samples;
    filters_ = params.filter_samples;
  }
}

void PcssPass::warm_up() {
  for (const char* k : {"pcss", "pcss_penumbra"}) pcss_kernel(k);
}

cl_kernel PcssPass::pcss_kernel(const char* name) {
  return kernels_.kernel("pcss.cl", name, pcss_shape(runtime_).options);
}

cl::Events PcssPass::launch_pcss(cl_kernel kernel, uint32_t count) const {
  const PixelShape shape = pcss_shape(runtime_);
  return runtime_.launch(kernel, shape.work_items(count), shape.group);
}

const cl::Buffer& PcssPass::run(const GBuffer& gb, uint32_t pixels, uint32_t width,
                                const cl::Buffer& map, const ViewSetup& light_view,
                                const Light& light, const ShadowMapSettings& settings,
                                const PcssSettings& params, Timeline& timeline) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  set_patterns(params, "visibility.pcss", timeline);
  const PcssGeometry geo = pcss_geometry(light_view, light, settings.size);
  cl_kernel k = pcss_kernel("pcss");
  cl::set_args(k, gb.position, gb.normal, pixels, width, shadow_lookup(light_view, light, settings),
               map, taps_, params.blocker_samples, params.filter_samples,
               static_cast<int>(params.rotate), static_cast<int>(geo.perspective), geo.alpha,
               geo.beta, geo.size, geo.scale, kMaxSearchTexels, visibility_);
  timeline.add("visibility.pcss", launch_pcss(k, pixels));
  return visibility_;
}

void PcssPass::penumbra(const GBuffer& view, uint32_t texels, uint32_t width, const cl::Buffer& map,
                        const ViewSetup& light_view, const Light& light,
                        const ShadowMapSettings& settings, const PcssSettings& params,
                        cl::Buffer& half_width, Timeline& timeline) {
  runtime_.ensure(half_width, size_t{texels} * sizeof(float));
  set_patterns(params, "atlas.penumbra", timeline);
  const PcssGeometry geo = pcss_geometry(light_view, light, settings.size);
  cl_kernel k = pcss_kernel("pcss_penumbra");
  cl::set_args(k, view.position, view.normal, texels, width,
               shadow_lookup(light_view, light, settings), map, taps_, params.blocker_samples,
               static_cast<int>(params.rotate), static_cast<int>(geo.perspective), geo.alpha,
               geo.beta, geo.size, geo.scale, kMaxSearchTexels, half_width);
  timeline.add("atlas.penumbra", launch_pcss(k, texels));
}

}  // namespace shadow
