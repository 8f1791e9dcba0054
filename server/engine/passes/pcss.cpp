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
  for (const char* k : {"pcss", "pcss_atlas", "pcss_penumbra", "atlas_footprint", "atlas_soften"})
    pcss_kernel(k);
  for (const char* k : {"atlas_chart_moments", "atlas_chart_base", "atlas_chart_mip"})
    atlas_kernel(k);
  chart_sat_.warm_up();
}

cl_kernel PcssPass::pcss_kernel(const char* name) {
  return kernels_.kernel("pcss.cl", name, pcss_shape(runtime_).options);
}

cl_kernel PcssPass::atlas_kernel(const char* name) {
  return kernels_.kernel("atlas.cl", name, pixel_shape(runtime_, kAtlasTexelChunk).options);
}

cl::Events PcssPass::launch_pcss(cl_kernel kernel, uint32_t count) const {
  const PixelShape shape = pcss_shape(runtime_);
  return runtime_.launch(kernel, shape.work_items(count), shape.group);
}

cl::Events PcssPass::launch_texels(cl_kernel kernel, uint32_t count) const {
  const PixelShape shape = pixel_shape(runtime_, kAtlasTexelChunk);
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

const cl::Buffer& PcssPass::footprint(const GBuffer& view, const cl::Buffer& texel_axes,
                                      const cl::Buffer& half_width, uint32_t texels,
                                      const ViewSetup& light_view, const Light& light,
                                      const ShadowMapSettings& settings, Timeline& timeline) {
  runtime_.ensure(footprint_, size_t{texels} * 3 * sizeof(float));
  cl_kernel k = pcss_kernel("atlas_footprint");
  cl::set_args(k, view.position, view.normal, texel_axes, half_width, texels,
               shadow_lookup(light_view, light, settings),
               pcss_geometry(light_view, light, settings.size).scale, footprint_);
  timeline.add("atlas.footprint", launch_pcss(k, texels));
  return footprint_;
}

void PcssPass::soften(const GBuffer& view, const ViewSetup& light_view, const Light& light,
                      const ShadowMapSettings& settings, const AtlasPrefiltered& atlas,
                      cl::Buffer& soft, Timeline& timeline) {
  const uint32_t texels = atlas.width * atlas.height;
  runtime_.ensure(soft, size_t{texels} * sizeof(uint32_t));
  runtime_.ensure(no_doubles_, 2 * sizeof(double));
  const bool use_sat = atlas.sat != nullptr;
  // Level 0 is the atlas; levels up to the one whose texel spans the largest tile follow (mips
  // only; a smaller tile's texels meet other tiles' charts sooner, and the chain marks them).
  level_table_.assign(1, glm::uvec4(atlas.width, atlas.height, 0, 0));
  const SummedAreaTable* moments = nullptr;
  if (use_sat) {
    runtime_.ensure(chart_moments_, size_t{texels} * 3 * sizeof(float));
    cl_kernel k = atlas_kernel("atlas_chart_moments");
    cl::set_args(k, view.position, view.normal, *atlas.texel_charts, texels, light_item(light),
                 chart_moments_);
    timeline.add("atlas.charts", launch_texels(k, texels));
    moments = &chart_sat_.run(DeviceTexture{&chart_moments_, atlas.width, atlas.height, 3},
                              "atlas.charts", timeline);
  } else {
    uint64_t floats = texels;
    for (uint32_t w = atlas.width, h = atlas.height, size = 2; size <= atlas.tile; size *= 2) {
      w = (w + 1) / 2, h = (h + 1) / 2;
      level_table_.emplace_back(w, h, uint32_t(floats), 0);
      floats += uint64_t{w} * h;
    }
    runtime_.ensure(chart_chain_, floats * 4 * sizeof(float));
    cl_kernel base = atlas_kernel("atlas_chart_base");
    cl::set_args(base, *atlas.level0, view.position, view.normal, *atlas.texel_charts, texels,
                 light_item(light), chart_chain_);
    timeline.add("atlas.charts", launch_texels(base, texels));
    cl_kernel down = atlas_kernel("atlas_chart_mip");
    for (size_t l = 1; l < level_table_.size(); ++l) {
      const glm::uvec4 &a = level_table_[l - 1], &b = level_table_[l];
      cl::set_args(down, chart_chain_, a.z, a.x, a.y, b.z, b.x, b.y);
      timeline.add("atlas.charts", launch_texels(down, b.x * b.y));
    }
  }
  runtime_.ensure(levels_, level_table_.size() * sizeof(glm::uvec4));
  timeline.add("atlas.soften", runtime_.write(levels_, level_table_.data(),
                                              level_table_.size() * sizeof(glm::uvec4)));
  runtime_.ensure(chart_chain_, 4 * sizeof(float));
  cl_kernel k = pcss_kernel("atlas_soften");
  const cl::Buffer& ellipses = footprint(view, *atlas.texel_axes, *atlas.half_width, texels,
                                         light_view, light, settings, timeline);
  cl::set_args(k, view.position, *atlas.half_width, ellipses, *atlas.texel_charts, texels,
               atlas.width, *atlas.cells, atlas.cell, int(use_sat),
               use_sat ? atlas.sat->sums : no_doubles_, use_sat ? moments->sums : no_doubles_,
               chart_chain_, levels_, uint32_t(level_table_.size() - 1), soft);
  timeline.add("atlas.soften", launch_pcss(k, texels));
}

const cl::Buffer& PcssPass::run_atlas(const GBuffer& gb, uint32_t pixels, const Light& light,
                                      const AtlasInputs& atlas, Timeline& timeline) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  cl_kernel k = pcss_kernel("pcss_atlas");
  cl::set_args(k, gb.position, gb.normal, pixels, light_item(light), *gb.ids, *gb.draws,
               gb.draw_count, atlas.scene->positions(), atlas.scene->indices(), *atlas.uvs,
               *atlas.tiles, *atlas.soft, atlas.width, visibility_);
  timeline.add("visibility.atlas", launch_pcss(k, pixels));
  return visibility_;
}

}  // namespace shadow
