#include "engine/passes/texel_density.hpp"

#include "engine/passes/light_args.hpp"

namespace shadow {

const cl::Buffer& TexelDensityPass::run(const GBuffer& g, const Camera& camera,
                                        const ViewSetup& camera_view, const ViewSetup& light_view,
                                        uint32_t map_size, Timeline& timeline) {
  const uint32_t pixels = camera.width * camera.height;
  runtime_.ensure(density_, size_t{pixels} * sizeof(float));
  const glm::mat4 light_to_ndc(light_view.world_to_ndc), camera_to_ndc(camera_view.world_to_ndc);
  cl_kernel k = kernels_.kernel("texel_density.cl", "texel_density", faces_option(light_view));
  cl::set_args(k, g.position, g.normal, pixels, light_to_ndc, map_size, camera_to_ndc, camera.width,
               camera.height, faces_args(light_view.faces), density_);
  timeline.add("texel_density.footprint", runtime_.launch(k, (pixels + 63) / 64));
  return density_;
}

}  // namespace shadow
