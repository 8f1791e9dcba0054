// shadow-raster-bench: the engine's shadow-map rasterization and its per-pixel shadow test,
// timed by the engine's own OpenCL profiling events (RenderResult::timings). Iteration time is
// the device time of the passes under test; the wall time of the whole request (scene upload,
// checks, readback) is a counter beside it.
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include <benchmark/benchmark.h>

#include "machine_context.hpp"

#include "engine/engine.hpp"
#include "oracle/scenes.hpp"

namespace shadow {
namespace {

Engine& engine() {
  static Engine e;  // kernels are built and warmed here, before any timing
  return e;
}

// Random triangles over a 100 m ground; 0.15 m edges are ~3 texels at 2048^2 (area ~4 texels).
constexpr float kExtent = 100.0f;
constexpr float kEdge = 0.15f;

const scenes::Setup& triangle_field(size_t count) {
  static std::map<size_t, scenes::Setup> cache;
  auto it = cache.find(count);
  if (it == cache.end())
    it = cache.emplace(count, scenes::random_triangles(count, kExtent, kEdge)).first;
  return it->second;
}

double pass_ms(const RenderResult& r, std::string_view prefix) {
  double ms = 0.0;
  for (const PassTiming& t : r.timings) {
    if (std::string_view(t.pass).starts_with(prefix)) ms += t.device_ms;
  }
  return ms;
}

double wall_ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

RenderRequest make_request(const scenes::Setup& s, uint32_t map_size, Product product) {
  RenderRequest r;
  r.scene = std::make_shared<Scene>(s.scene);
  r.camera = s.camera;
  r.light = s.light;
  r.shadow_map.size = map_size;
  r.products = {product};
  return r;
}

// Every pass whose name starts with "shadow_map." (transform, setup, bin, raster).
void BM_ShadowMapRaster(benchmark::State& state) {
  const auto tris = static_cast<size_t>(state.range(0));
  const auto size = static_cast<uint32_t>(state.range(1));
  const RenderRequest req = make_request(triangle_field(tris), size, Product::kShadowMap);
  // Warm-up: first use of a map size allocates buffers; the second render is steady state.
  RenderResult first = engine().render(req);
  engine().render(req);
  const glm::mat4& m = first.textures.at(0).world_to_ndc;
  const double texels_per_metre = size * glm::length(glm::vec3(m[0][0], m[1][0], m[2][0]));

  double device = 0.0, wall = 0.0;
  std::map<std::string, double> per_pass;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const RenderResult r = engine().render(req);
    wall += wall_ms_since(start);
    const double ms = pass_ms(r, "shadow_map.");
    device += ms;
    for (const PassTiming& t : r.timings) {
      if (t.pass.starts_with("shadow_map.")) per_pass[t.pass.substr(11) + "_ms"] += t.device_ms;
    }
    state.SetIterationTime(ms / 1e3);
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["tris_per_s"] = tris * n / (device / 1e3);
  state.counters["wall_ms"] = wall / n;
  for (const auto& [name, ms] : per_pass) state.counters[name] = ms / n;
  state.counters["edge_texels"] = kEdge * texels_per_metre;
}

// The shadow test alone ("visibility." passes); the g-buffer and the map are counters.
void BM_ShadowTest(benchmark::State& state) {
  scenes::Setup s = scenes::test_scene();
  s.camera.width = static_cast<uint32_t>(state.range(0));
  s.camera.height = static_cast<uint32_t>(state.range(1));
  const RenderRequest req = make_request(s, 2048, Product::kVisibility);
  engine().render(req);
  engine().render(req);

  double device = 0.0, gbuffer = 0.0, map = 0.0, wall = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const RenderResult r = engine().render(req);
    wall += wall_ms_since(start);
    const double ms = pass_ms(r, "visibility.");
    device += ms;
    gbuffer += pass_ms(r, "gbuffer.");
    map += pass_ms(r, "shadow_map.");
    state.SetIterationTime(ms / 1e3);
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["pixels_per_s"] =
      static_cast<double>(s.camera.width) * s.camera.height * n / (device / 1e3);
  state.counters["gbuffer_ms"] = gbuffer / n;
  state.counters["shadow_map_ms"] = map / n;
  state.counters["wall_ms"] = wall / n;
}

BENCHMARK(BM_ShadowMapRaster)
    ->ArgNames({"tris", "map"})
    ->ArgsProduct({{10000, 100000, 1000000}, {1024, 2048, 4096}})
    ->MinTime(1.0)  // seconds of device time: several iterations even for the slow cases
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ShadowTest)
    ->ArgNames({"w", "h"})
    ->Args({1280, 720})
    ->Args({1920, 1080})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace shadow

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  shadow::bench::add_machine_context(shadow::engine().device_name());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
