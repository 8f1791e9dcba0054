#include "engine/passes/gbuffer.hpp"

namespace shadow {

const GBuffer& GBufferPass::run(const Scene& scene, const SceneBuffers& buffers,
                                const Camera& camera, const ViewSetup& view, Timeline& timeline) {
  std::vector<DrawItem> draws = make_draws(scene, buffers, glm::mat4(view.world_to_ndc),
                                           [](const Instance&) { return true; });
  const RasterOutput& raster = rasterizer_.run(buffers, draws, camera.width, camera.height, true,
                                               "gbuffer", "camera.width", timeline);

  GBuffer& g = buffers_;
  g.ids = &raster.ids;
  g.draws = &raster.draws;
  g.draw_count = static_cast<uint32_t>(draws.size());
  const CameraRays rays = camera_rays(camera);
  StepCache* cache = rasterizer_.cache();
  uint64_t key = 0;
  if (cache && cache->keeping()) {  // the raster's result, by its version, and the rays
    key = StepKey{}
              .add(&raster, raster.version)
              .add(rays.eye)
              .add(rays.ray_00)
              .add(rays.ray_du)
              .add(rays.ray_dv)
              .value();
    if (cache->take("gbuffer", key, "gbuffer.resolve", timeline)) return g;
  }
  const uint32_t pixels = camera.width * camera.height;
  runtime_.ensure(g.position, size_t{pixels} * 3 * sizeof(float));
  runtime_.ensure(g.normal, size_t{pixels} * 4 * sizeof(float));
  const uint32_t draw_count = static_cast<uint32_t>(draws.size());
  const PixelShape shape = gbuffer_shape(runtime_);
  cl_kernel k = kernels_.kernel("gbuffer.cl", "resolve_gbuffer", shape.options);
  cl::set_args(k, raster.ids, camera.width, pixels, rays.eye, rays.ray_00, rays.ray_du, rays.ray_dv,
               buffers.positions(), buffers.indices(), raster.draws, draw_count, g.position,
               g.normal);
  timeline.add("gbuffer.resolve", runtime_.launch(k, shape.work_items(pixels), shape.group));
  if (cache) cache->made("gbuffer", key);  // one set of buffers, whatever the timeline's prefix
  return g;
}

}  // namespace shadow
