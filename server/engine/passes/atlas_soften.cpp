#include "engine/passes/atlas_soften.hpp"

#include "engine/passes/light_args.hpp"
#include "engine/passes/pcss.hpp"
#include "engine/passes/pixel_shape.hpp"

namespace shadow {

void AtlasSoftenPass::warm_up() {
  for (const char* k : {"atlas_footprint", "atlas_soften", "atlas_lookup", "atlas_chart_moments",
                        "atlas_chart_base", "atlas_chart_mip"})
    kernel(k);
  chart_sat_.warm_up();
}

// One program serves both chunk sizes: the options of a shape do not depend on the strip.
cl_kernel AtlasSoftenPass::kernel(const char* name) {
  return kernels_.kernel("atlas_soften.cl", name, pixel_shape(runtime_, kSoftChunk).options);
}

cl::Events AtlasSoftenPass::launch_soft(cl_kernel kernel, uint32_t count) const {
  const PixelShape shape = pixel_shape(runtime_, kSoftChunk);
  return runtime_.launch(kernel, shape.work_items(count), shape.group);
}

cl::Events AtlasSoftenPass::launch_texels(cl_kernel kernel, uint32_t count) const {
  const PixelShape shape = pixel_shape(runtime_, kChartChunk);
  return runtime_.launch(kernel, shape.work_items(count), shape.group);
}

const cl::Buffer& AtlasSoftenPass::footprint(const GBuffer& view, const cl::Buffer& texel_axes,
                                             const cl::Buffer& half_width, uint32_t texels,
                                             const ViewSetup& light_view, const Light& light,
                                             const ShadowMapSettings& settings,
                                             Timeline& timeline) {
  runtime_.ensure(footprint_, size_t{texels} * 3 * sizeof(float));
  cl_kernel k = kernel("atlas_footprint");
  cl::set_args(k, view.position, view.normal, texel_axes, half_width, texels,
               shadow_lookup(light_view, light, settings),
               pcss_geometry(light_view, light, settings.size).scale, footprint_);
  timeline.add("atlas.footprint", launch_soft(k, texels));
  return footprint_;
}

void AtlasSoftenPass::soften(const GBuffer& view, const ViewSetup& light_view, const Light& light,
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
    cl_kernel k = kernel("atlas_chart_moments");
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
    cl_kernel base = kernel("atlas_chart_base");
    cl::set_args(base, *atlas.level0, view.position, view.normal, *atlas.texel_charts, texels,
                 light_item(light), chart_chain_);
    timeline.add("atlas.charts", launch_texels(base, texels));
    cl_kernel down = kernel("atlas_chart_mip");
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
  cl_kernel k = kernel("atlas_soften");
  const cl::Buffer& ellipses = footprint(view, *atlas.texel_axes, *atlas.half_width, texels,
                                         light_view, light, settings, timeline);
  cl::set_args(k, view.position, *atlas.half_width, ellipses, *atlas.texel_charts, texels,
               atlas.width, *atlas.cells, atlas.cell, int(use_sat),
               use_sat ? atlas.sat->sums : no_doubles_, use_sat ? moments->sums : no_doubles_,
               chart_chain_, levels_, uint32_t(level_table_.size() - 1), soft);
  timeline.add("atlas.soften", launch_soft(k, texels));
}

const cl::Buffer& AtlasSoftenPass::lookup(const GBuffer& gb, uint32_t pixels, const Light& light,
                                          const AtlasInputs& atlas, Timeline& timeline) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  cl_kernel k = kernel("atlas_lookup");
  cl::set_args(k, gb.position, gb.normal, pixels, light_item(light), *gb.ids, *gb.draws,
               gb.draw_count, atlas.scene->positions(), atlas.scene->indices(), *atlas.uvs,
               *atlas.tiles, *atlas.soft, atlas.width, visibility_);
  timeline.add("visibility.atlas", launch_soft(k, pixels));
  return visibility_;
}

}  // namespace shadow
