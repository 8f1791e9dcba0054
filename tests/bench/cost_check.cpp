// cost-check: the admission estimate (engine/plan/cost.hpp) against what Engine::render measures
// in-process: the time (the render in its workspace, host work included: what the runtime guard
// and a waiting client see) and the device memory (the peak of the buffers alone, each request
// starting from empty workspaces). One markdown row per case, on a grid of every technique,
// filter and product, the large requests issue 51 found under-priced, and (--sweep) the
// product-hashes sweep. The engine has the server's default memory budget, so what the server
// would refuse shows as refused.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/engine.hpp"
#include "engine/plan/cost.hpp"
#include "engine/plan/plan.hpp"
#include "estimate_grid.hpp"
#include "scenes/shapes.hpp"
#include "sweep.hpp"
#include "wire/names.hpp"

namespace {

using namespace shadow;

bool show_passes = false;  // --passes: each step's estimate and its passes' device time

// Ratios outside [0.5, 3] are marked, the bounds issue 51 holds the estimates to.
const char* mark(double ratio) {
  return ratio < 0.5 || ratio > 3 ? " **" : "";
}

void run(Engine& engine, const std::string& name, const RenderRequest& req) {
  const CostEstimate cost = estimate_cost(req, make_plan(req));
  engine.reset_buffer_peak();
  RenderResult result;
  try {
    result = engine.render(req);
  } catch (const std::exception& e) {
    std::printf("| %s | %.0f | refused: %s |||||\n", name.c_str(), cost.ms, e.what());
    std::fflush(stdout);
    return;
  }
  double device = 0;
  for (const PassTiming& t : result.timings) device += t.device_ms;
  const double peak_mib = double(engine.buffer_peak_bytes()) / (1 << 20);
  const double est_mib = double(cost.device_bytes) / (1 << 20);
  const double time_ratio = cost.ms / result.run_ms, memory_ratio = est_mib / peak_mib;
  std::printf("| %s | %.0f | %.0f | %.0f | %.2f%s | %.0f | %.0f | %.2f%s |\n", name.c_str(),
              cost.ms, device, result.run_ms, time_ratio, mark(time_ratio), est_mib, peak_mib,
              memory_ratio, mark(memory_ratio));
  if (show_passes) {
    // Each step's estimate beside the device time of its passes (named with the step's prefix).
    std::map<std::string, double> by_pass;
    for (const PassTiming& t : result.timings) by_pass[t.pass] += t.device_ms;
    for (const StepCost& step : cost.steps) {
      double est = 0, measured = 0;
      for (size_t i = 0; i < kCostRates; ++i) est += step.units[i] * admission_rates().ns[i] * 1e-6;
      for (auto& [pass, ms] : by_pass)
        if (pass.rfind(step.step, 0) == 0) measured += std::exchange(ms, 0.0);
      std::printf("|   %s | %.1f | %.1f |||||\n", step.step.c_str(), est, measured);
    }
    for (const auto& [pass, ms] : by_pass)
      if (ms > 0) std::printf("|   (%s) | | %.1f |||||\n", pass.c_str(), ms);
  }
  std::fflush(stdout);
}

RenderRequest demo(uint32_t width, uint32_t height, uint32_t map, FilterKind filter) {
  return testing::demo_request(width, height, map, filter);
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

// The requests issue 51 measured at 1.8-4.5x their estimate, and sizes near the limits.
void large(Engine& engine) {
  for (LightType type : {LightType::kSpot, LightType::kDirectional}) {
    RenderRequest r = demo(2048, 2048, 8192, FilterKind::kPcss);
    if (type == LightType::kSpot) {
      r.lights[0].type = LightType::kSpot;
      r.lights[0].position = {6, 14, 6};
      r.lights[0].direction = glm::normalize(glm::vec3(-6, -14, -6));
      r.lights[0].cone_angle_deg = 70;
      r.lights[0].size = 50;
    } else {
      r.lights[0].size = 3;
    }
    run(engine,
        std::string("large: pcss 64/64, ") + (type == LightType::kSpot ? "spot" : "sun") +
            ", 8192, 2048^2 view",
        r);
  }
  run(engine, "large: pcss 64/64, sun, 8192, 1080p", demo(1920, 1080, 8192, FilterKind::kPcss));
  {
    RenderRequest r = demo(1920, 1080, 2048, FilterKind::kCsm);
    r.filter.csm.terms = 16;
    r.filter.csm.lookup = CsmLookup::kSat;
    r.products = {Product::kVisibility, Product::kShadowMapSat, Product::kVisibilitySat};
    run(engine, "large: csm M16 sat, 2048, 1080p, SAT products", r);
  }
  for (uint32_t map : {4096u, 8192u}) {
    RenderRequest r = demo(1920, 1080, map, FilterKind::kCsm);
    r.filter.csm.terms = 8;
    r.filter.csm.storage = CsmStorage::kFloat16;
    run(engine, "large: csm M8 float16, " + std::to_string(map) + ", 1080p", r);
  }
  for (uint32_t map : {4096u, 8192u}) {
    RenderRequest r = demo(1280, 720, map, FilterKind::kCsm);
    r.filter.csm.terms = 16;
    r.products = {Product::kShadowMapSat};
    run(engine, "large: csm M16, " + std::to_string(map) + ", shadowmap_sat, 720p", r);
  }
  run(engine, "large: hard, 8192, 8K view", demo(7680, 4320, 8192, FilterKind::kHard));
  run(engine, "large: 1M-triangle ground, 8192, 1080p", fine_ground(708, 8192));
  run(engine, "large: 1000 x 10k-triangle spheres, 4096, 720p", many_instances(1000, 4096));
  run(engine, "large: 4k whole-map triangles, 2048", overlapping(4096, 2048));
}

}  // namespace

int main(int argc, char** argv) {
  EngineOptions options;
  options.max_request_cost_ms = 0;  // measure everything
  options.max_output_bytes = uint64_t{4} << 30;
  // Each request starts from empty workspaces, so its buffer peak is its own.
  options.idle_trim_delay_ms = 0;
  options.idle_memory_bytes = 0;
  options.max_concurrent = 1;
  Engine engine(options);
  std::set<std::string> parts;
  for (int i = 1; i < argc; ++i) parts.insert(argv[i]);
  show_passes = parts.erase("--passes") > 0;
  if (parts.empty()) parts = {"--grid", "--large"};
  std::printf(
      "| case | estimate ms | device ms | run ms | estimate / run | estimate MiB | peak "
      "MiB | estimate / peak |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  if (parts.count("--grid"))
    for (const testing::EstimateCase& c : testing::estimate_grid(1280, 720, 2048, 4096))
      run(engine, "grid: " + c.name, c.request);
  if (parts.count("--large")) large(engine);
  if (parts.count("--sweep"))
    bench::for_each_sweep_case(
        [&](const std::string& name, const RenderRequest& req) { run(engine, name, req); });
  return 0;
}
