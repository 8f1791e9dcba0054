// cost-check: the admission estimate (engine/plan/cost.hpp) against the measured wall time of
// Engine::render in-process, on the product-hashes sweep and on large requests near the default
// limit. Prints one line per case: estimate, measured, and their ratio.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/engine.hpp"
#include "engine/plan/cost.hpp"
#include "engine/plan/plan.hpp"
#include "scenes/shapes.hpp"
#include "sweep.hpp"

namespace {

using namespace shadow;

void run(Engine& engine, const std::string& name, const RenderRequest& req) {
  const CostEstimate cost = estimate_cost(req, make_plan(req));
  const auto t0 = std::chrono::steady_clock::now();
  try {
    engine.render(req);
  } catch (const std::exception& e) {
    std::printf("%-48s refused: %s\n", name.c_str(), e.what());
    return;
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%-48s estimate %9.1f ms  measured %9.1f ms  ratio %5.2f  (%s)\n", name.c_str(),
              cost.ms, ms, cost.ms / ms, cost.driver.c_str());
}

RenderRequest demo(uint32_t width, uint32_t height, uint32_t map, FilterKind filter) {
  const scenes::DemoSetup d = scenes::demo_scene();
  RenderRequest r;
  r.scene = std::make_shared<Scene>(d.scene);
  r.camera = d.camera;
  r.camera.width = width;
  r.camera.height = height;
  r.lights = {d.light};
  r.lights[0].size = 1.0f;
  r.shadow_map = d.shadow_map;
  r.shadow_map.size = map;
  r.filter.kind = filter;
  r.filter.pcss.blocker_samples = r.filter.pcss.filter_samples = 64;
  r.filter.poisson.taps = 64;
  r.products = {Product::kVisibility};
  return r;
}

// Twelve spheres over a ground, all receiving in their own UVs (shadow-atlas-bench's scene).
RenderRequest atlas_scene(uint32_t tile) {
  RenderRequest r = demo(1280, 720, 2048, FilterKind::kHard);
  auto scene = std::make_shared<Scene>();
  scene->meshes = {scenes::make_grid(24.0f, 8), scenes::make_sphere(32, 16)};
  scene->instances = {Instance{0}};
  for (int i = 0; i < 12; ++i) {
    Instance s{1};
    s.transform =
        glm::translate(glm::mat4(1.0f), glm::vec3(3 * (i % 4) - 4.5f, 1.5f, 3 * (i / 4) - 3.0f));
    scene->instances.push_back(s);
  }
  r.scene = scene;
  r.shadow_map.fit = MapFit::kScene;
  r.shadow_map.technique = Technique::kUniform;
  r.atlas.tile = tile;
  r.filter.pcss.blocker_samples = 16;
  return r;
}

// `cells`^2 quads of ground as one mesh: 2 cells^2 small triangles.
RenderRequest fine_ground(int cells, uint32_t map) {
  RenderRequest r = demo(1920, 1080, map, FilterKind::kHard);
  auto scene = std::make_shared<Scene>(*r.scene);
  scene->meshes[0] = scenes::make_grid(40.0f, cells);
  r.scene = scene;
  r.products = {Product::kShadowMap, Product::kVisibility};
  return r;
}

// `n` triangles that each cover the whole ground: every one lands in every map tile.
RenderRequest overlapping(uint32_t n, uint32_t map) {
  RenderRequest r = demo(640, 360, map, FilterKind::kHard);
  auto scene = std::make_shared<Scene>(*r.scene);
  Mesh m;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> y(0.5f, 3.0f);
  for (uint32_t i = 0; i < n; ++i) {
    const float h = y(rng);
    m.positions.insert(m.positions.end(), {-40, h, -40, 40, h, -40, 0, h, 40});
    m.indices.insert(m.indices.end(), {3 * i, 3 * i + 2, 3 * i + 1});
  }
  scene->meshes.push_back(m);
  Instance inst;
  inst.mesh = uint32_t(scene->meshes.size() - 1);
  scene->instances.push_back(inst);
  r.scene = scene;
  r.products = {Product::kShadowMap};
  return r;
}

// `n` instances of a 10k-triangle sphere in a grid.
RenderRequest many_instances(uint32_t n, uint32_t map) {
  RenderRequest r = demo(1280, 720, map, FilterKind::kHard);
  auto scene = std::make_shared<Scene>(*r.scene);
  scene->meshes.push_back(scenes::make_sphere(100, 50));
  const uint32_t side = uint32_t(std::ceil(std::sqrt(double(n))));
  for (uint32_t i = 0; i < n; ++i) {
    Instance inst;
    inst.mesh = uint32_t(scene->meshes.size() - 1);
    inst.transform = glm::scale(
        glm::translate(glm::mat4(1.0f), glm::vec3(-15.0f + 30.0f * (i % side) / side, 0.3f,
                                                  -15.0f + 30.0f * (i / side) / side)),
        glm::vec3(0.2f));
    scene->instances.push_back(inst);
  }
  r.scene = scene;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  EngineOptions options;
  options.max_request_cost_ms = 0;  // measure everything
  options.max_output_bytes = uint64_t{4} << 30;
  Engine engine(options);
  const bool sweep = argc > 1 && std::string(argv[1]) == "--sweep";
  if (sweep)
    bench::for_each_sweep_case(
        [&](const std::string& name, const RenderRequest& req) { run(engine, name, req); });
  run(engine, "demo 1080p pcss 64/64, 2048", demo(1920, 1080, 2048, FilterKind::kPcss));
  run(engine, "demo 1080p poisson 64, 2048", demo(1920, 1080, 2048, FilterKind::kPoisson));
  run(engine, "demo 4K pcss 64/64, 4096", demo(3840, 2160, 4096, FilterKind::kPcss));
  run(engine, "demo 8K pcss 64/64, 2048", demo(7680, 4320, 2048, FilterKind::kPcss));
  run(engine, "demo 8K hard, 8192", demo(7680, 4320, 8192, FilterKind::kHard));
  for (uint32_t terms : {4u, 8u, 16u}) {
    for (FilterKind kind : {FilterKind::kCsm, FilterKind::kPcssCsm}) {
      RenderRequest r = demo(1920, 1080, 2048, kind);
      r.filter.csm.terms = terms;
      run(engine,
          std::string("demo 1080p ") + (kind == FilterKind::kCsm ? "csm" : "pcss_csm") + " M" +
              std::to_string(terms) + ", 2048",
          r);
    }
  }
  for (uint32_t tile : {256u, 512u})
    for (FilterKind kind : {FilterKind::kAtlasSat, FilterKind::kAtlasMip}) {
      RenderRequest r = atlas_scene(tile);
      r.filter.kind = kind;
      run(engine,
          std::string("spheres 720p ") +
              (kind == FilterKind::kAtlasSat ? "atlas_sat" : "atlas_mip") + ", tiles of " +
              std::to_string(tile),
          r);
    }
  run(engine, "1M-triangle ground, 4096, 1080p", fine_ground(708, 4096));
  run(engine, "1M-triangle ground, 8192, 1080p", fine_ground(708, 8192));
  run(engine, "4k whole-map triangles, 2048", overlapping(4096, 2048));
  run(engine, "16k whole-map triangles, 2048", overlapping(16384, 2048));
  run(engine, "300 x 10k-triangle spheres, 2048, 720p", many_instances(300, 2048));
  run(engine, "1000 x 10k-triangle spheres, 4096, 720p", many_instances(1000, 4096));
  return 0;
}
