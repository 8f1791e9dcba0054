#include "engine/passes/pcss.hpp"

#include "engine/passes/light_args.hpp"

#include <algorithm>
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

glm::vec4 pcss_search_bound(const VirtualLevels& layout, const Light& light) {
  if (!layout.perspective())
    return glm::vec4(float(std::tan(glm::radians(0.5 * light.size))), float(layout.depth.near),
                     float(layout.texels), 0.0f);
  const ViewSetup& face = layout.levels.front().setup;
  const PcssGeometry g = pcss_geometry(face, light, layout.texels);
  return glm::vec4(light.size, float(face.depth.near), std::max(g.scale.x, g.scale.y), 0.0f);
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
  pcss_kernel("pcss", true);
}

cl_kernel PcssPass::pcss_kernel(const char* name, bool paged) {
  return kernels_.kernel("pcss.cl", name,
                         pcss_shape(runtime_).options + (paged ? " -DVIRTUAL" : ""));
}

cl::Events PcssPass::launch_pcss(cl_kernel kernel, uint32_t count) const {
  const PixelShape shape = pcss_shape(runtime_);
  return runtime_.launch(kernel, shape.work_items(count), shape.group);
}

const cl::Buffer& PcssPass::run(const GBuffer& gb, uint32_t pixels, uint32_t width,
                                const cl::Buffer& map, const ViewSetup& light_view,
                                const Light& light, const ShadowMapSettings& settings,
                                const PcssSettings& params, Timeline& timeline,
                                const VirtualMap* pages) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  set_patterns(params, "visibility.pcss", timeline);
  const PcssGeometry geo = pcss_geometry(light_view, light, settings.size);
  cl_kernel k = pcss_kernel("pcss", pages != nullptr);
  cl::set_args(k, gb.position, gb.normal, pixels, width, shadow_lookup(light_view, light, settings),
               map, taps_, params.blocker_samples, params.filter_samples,
               static_cast<int>(params.rotate), static_cast<int>(geo.perspective), geo.alpha,
               geo.beta, geo.size, geo.scale, pages ? kMaxVirtualSearch : kMaxSearchTexels,
               visibility_);
  if (pages) {  // VIRTUAL's arguments follow `visibility`: each level's geometry
    const VirtualLevels& layout = pages->layout;
    geometry_table_.clear();
    for (size_t i = 0; i < layout.levels.size(); ++i) {
      const PcssGeometry g = pcss_geometry(layout.levels[i].setup, light, layout.extent(i));
      geometry_table_.emplace_back(g.alpha, g.beta, g.scale.x, g.scale.y);
    }
    const size_t bytes = geometry_table_.size() * sizeof(glm::vec4);
    runtime_.ensure(level_geometry_, bytes);
    timeline.add("visibility.pcss", runtime_.write(level_geometry_, geometry_table_.data(), bytes));
    cl::set_arg(k, 17, pages->table);
    cl::set_arg(k, 18, pages->level_ndc);
    cl::set_arg(k, 19, pages->level_texels);
    cl::set_arg(k, 20, level_geometry_);
    cl::set_arg(k, 21, pages->pixel_level);
  }
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
