#include "engine/engine.hpp"

#include <algorithm>
#include <mutex>

#include "engine/cl/program_cache.hpp"
#include "engine/light_space.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/passes/shadow_test.hpp"
#include "engine/passes/texel_density.hpp"
#include "engine/scene_buffers.hpp"
#include "engine/validate.hpp"

namespace shadow {
namespace {

bool wants(const RenderRequest& r, Product p) {
  return std::find(r.products.begin(), r.products.end(), p) != r.products.end();
}

std::vector<InstanceBounds> instance_bounds(const Scene& scene, const SceneBuffers& buffers) {
  std::vector<InstanceBounds> out;
  for (const Instance& inst : scene.instances) {
    out.push_back({transform_bounds(buffers.meshes()[inst.mesh].bounds, glm::dmat4(inst.transform)),
                   inst.casts_shadows, inst.receives_shadows});
  }
  return out;
}

// A one-triangle scene that runs every pass once, so no request pays for a compile.
RenderRequest warm_up_request() {
  auto scene = std::make_shared<Scene>();
  Mesh m;
  m.positions = {-1,    0,    -1,    1,    0,    -1,    0, 0,    1,
                 -0.2f, 0.5f, -0.2f, 0.2f, 0.5f, -0.2f, 0, 0.5f, 0.2f};
  m.indices = {0, 1, 2, 3, 4, 5};
  scene->meshes.push_back(m);
  scene->instances.push_back(Instance{});
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 3, 3};
  r.camera.width = 64;
  r.camera.height = 64;
  r.shadow_map.size = 256;
  r.products = {Product::kShadowMap, Product::kVisibility, Product::kPosition,
                Product::kTexelDensity};
  return r;
}

}  // namespace

struct Engine::Impl {
  explicit Impl(EngineOptions o)
      : options(o),
        programs(runtime),
        rasterizer(runtime, programs),
        gbuffer(runtime, programs, rasterizer),
        shadow_test(runtime, programs),
        texel_density(runtime, programs) {}

  RenderResult render(const RenderRequest& request);
  Texture read_texture(const cl::Buffer& buffer, std::string name, Product kind, uint32_t w,
                       uint32_t h, uint32_t channels, Timeline& timeline);

  EngineOptions options;
  cl::Runtime runtime;
  cl::ProgramCache programs;
  Rasterizer rasterizer;
  GBufferPass gbuffer;
  ShadowTestPass shadow_test;
  TexelDensityPass texel_density;
  std::mutex mutex;  // one in-order queue: one request at a time
};

Texture Engine::Impl::read_texture(const cl::Buffer& buffer, std::string name, Product kind,
                                   uint32_t w, uint32_t h, uint32_t channels, Timeline& timeline) {
  Texture t;
  t.name = std::move(name);
  t.kind = kind;
  t.width = w;
  t.height = h;
  t.channels = channels;
  t.data.resize(size_t{w} * h * channels);
  timeline.add("readback", runtime.read(buffer, t.data.data(), t.byte_size()));
  return t;
}

RenderResult Engine::Impl::render(const RenderRequest& req) {
  validate(req, {options.max_output_bytes, runtime.max_alloc_bytes()});
  const Scene& scene = *req.scene;
  Timeline timeline;
  SceneBuffers buffers(runtime, programs, scene, timeline);

  // Plan: only the passes the requested products need.
  const bool need_map = wants(req, Product::kShadowMap) || wants(req, Product::kVisibility);
  const bool need_view = wants(req, Product::kVisibility) || wants(req, Product::kPosition) ||
                         wants(req, Product::kTexelDensity);
  // Texel density needs the light's matrix, not the rasterized map.
  const bool need_light = need_map || wants(req, Product::kTexelDensity);
  const ViewSetup camera = camera_setup(req.camera);
  const uint32_t pixels = req.camera.width * req.camera.height;

  ViewSetup light;
  const RasterOutput* map = nullptr;
  if (need_light) light = fit_uniform_light(req.light, req.camera, instance_bounds(scene, buffers));
  if (need_map) {
    auto draws = make_draws(scene, buffers, glm::mat4(light.world_to_ndc),
                            [](const Instance& i) { return i.casts_shadows; });
    map = &rasterizer.run(buffers, draws, req.shadow_map.size, req.shadow_map.size, false,
                          "shadow_map", "shadow_map.size", timeline);
  }
  const GBuffer* view =
      need_view ? &gbuffer.run(scene, buffers, req.camera, camera, timeline) : nullptr;

  RenderResult result;
  for (Product p : req.products) {
    Texture t;
    if (p == Product::kShadowMap) {
      t = read_texture(map->depth, "shadowmap", p, req.shadow_map.size, req.shadow_map.size, 1,
                       timeline);
      t.world_to_ndc = glm::mat4(light.world_to_ndc);
      t.world_to_camera = glm::mat4(light.view);
    } else {
      if (p == Product::kVisibility) {
        const cl::Buffer& vis =
            shadow_test.run(*view, pixels, map->depth, light, req.light, req.shadow_map, timeline);
        t = read_texture(vis, "visibility", p, req.camera.width, req.camera.height, 1, timeline);
      } else if (p == Product::kTexelDensity) {
        const cl::Buffer& density =
            texel_density.run(*view, req.camera, camera, light, req.shadow_map.size, timeline);
        t = read_texture(density, "texel_density", p, req.camera.width, req.camera.height, 1,
                         timeline);
      } else {
        t = read_texture(view->position, "position", p, req.camera.width, req.camera.height, 3,
                         timeline);
      }
      t.world_to_ndc = glm::mat4(camera.world_to_ndc);
      t.world_to_camera = glm::mat4(camera.view);
    }
    result.textures.push_back(std::move(t));
  }
  runtime.finish();
  result.passes = timeline.passes();
  if (options.profile) result.timings = timeline.timings();
  return result;
}

Engine::Engine(EngineOptions options) : impl_(std::make_unique<Impl>(options)) {
  impl_->rasterizer.warm_up();
  impl_->gbuffer.warm_up();
  impl_->shadow_test.warm_up();
  impl_->texel_density.warm_up();
  impl_->render(warm_up_request());
}

Engine::~Engine() = default;

RenderResult Engine::render(const RenderRequest& request) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->render(request);
}

const EngineOptions& Engine::options() const {
  return impl_->options;
}
std::string Engine::device_name() const {
  return impl_->runtime.device_name();
}

}  // namespace shadow
