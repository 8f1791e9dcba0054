#include "engine/passes/texel_density.hpp"

namespace shadow {

const cl::Buffer& TexelDensityPass::run(const GBuffer& g, const Camera& camera,
                                        const ViewSetup& camera_view,
                                        const std::vector<LightMap>& maps, uint32_t map_size,
                                        Timeline& timeline) {
  const uint32_t pixels = camera.width * camera.height;
  runtime_.ensure(density_, size_t{pixels} * sizeof(float));
  // Only the matrices: the maps themselves need not be rendered.
  const MapLookup m = map_lookup(maps, Light{}, ShadowMapSettings{});
  const glm::mat4 camera_to_ndc(camera_view.world_to_ndc);
  const PixelShape shape = texel_density_shape(runtime_);
  cl_kernel k = kernels_.kernel("texel_density.cl", "texel_density", shape.with(m.option));
  cl::set_args(k, g.position, g.normal, pixels, m.lookup.to_ndc, m.faces, m.cube, map_size,
               camera_to_ndc, camera.width, camera.height, density_);
  timeline.add("texel_density.footprint",
               runtime_.launch(k, shape.work_items(pixels), shape.group));
  return density_;
}

}  // namespace shadow
