// shadow-raster-bench: the engine's shadow-map rasterization and its per-pixel shadow test,
// timed by the engine's own OpenCL profiling events (RenderResult::timings). Iteration time is
// the device time of the passes under test; the wall time of the whole request (scene upload,
// checks, readback) is a counter beside it.
//   BM_VsGlPeer: the rasterizer alone (transform .. raster) against OpenGL through EGL
//     (egl_peer.hpp: the GPU's rasterizer, or Mesa's llvmpipe with LP_NUM_THREADS=2 where there
//     is none) on the same triangles and orthographic matrix, alternating per iteration;
//     medians, and their ratios `lead` = gl wall / ours and `gpu_lead` = gl timer query / ours.
//     The renderer is the `gl_peer` context line and each case's label.
//   BM_RasterPath: each kernel path (RasterPaths) switched against the defaults, alternating
//     per iteration: off_ms is the switched variant, on_ms the defaults.
//   BM_Filter1080p, BM_FullRequest: issue 42's per-pixel rows (each filter at 1080p) and its
//     full request (the forest, a 4096^2 map, 1080p, PCSS), every pass a counter.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <benchmark/benchmark.h>

#include "egl_peer.hpp"
#include "machine_context.hpp"
#include "raster_scenes.hpp"
#include "stream_bandwidth.hpp"

#include "engine/engine.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine_fixture.hpp"
#include "oracle/scenes.hpp"
#include "oracle/standard_scenes.hpp"

namespace shadow {
namespace {

using testing::engine;  // kernels are built and warmed on first use, before any timing

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
  r.lights = {s.light};
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

// The shadow test alone ("visibility." passes); the g-buffer and the map are counters, each
// beside its memory floor: the g-buffer reads an id and writes a position and a normal (4 + 12
// + 16 bytes a pixel), the test reads those and one map texel and writes the visibility
// (12 + 16 + 4 + 4); the triangles and map texels reused from cache are not counted.
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
  const double pixels = double(s.camera.width) * s.camera.height;
  state.counters["gbuffer_floor_ms"] = bench::floor_ms(32 * pixels);
  state.counters["test_ms"] = device / n;
  state.counters["test_floor_ms"] = bench::floor_ms(36 * pixels);
  state.counters["stream_GBps"] = bench::stream_bytes_per_s() / 1e9;
  state.counters["shadow_map_ms"] = map / n;
  state.counters["wall_ms"] = wall / n;
}

// Each filter of issue 42's per-pixel rows at 1080p (test_scene, a 2048^2 map): the iteration
// time is the filter's own passes: "visibility." and, for CSM, "csm." (its basis and mips); the
// g-buffer, the map and every other pass are counters.
struct FilterCase {
  const char* name;
  Filter filter;
};

const std::vector<FilterCase>& filter_cases() {
  static const std::vector<FilterCase> cases = [] {
    std::vector<FilterCase> c;
    Filter f;
    c.push_back({"hard", f});
    f.kind = FilterKind::kPcf2x2;
    c.push_back({"pcf2x2", f});
    f.kind = FilterKind::kPoisson;
    f.poisson.taps = 64;
    c.push_back({"poisson64", f});
    f.kind = FilterKind::kPcss;  // 16 blocker and 32 filter samples, the defaults
    c.push_back({"pcss16_32", f});
    f.kind = FilterKind::kCsm;  // M = 8, the default
    c.push_back({"csm8", f});
    return c;
  }();
  return cases;
}

void BM_Filter1080p(benchmark::State& state) {
  const FilterCase& c = filter_cases().at(static_cast<size_t>(state.range(0)));
  scenes::Setup s = scenes::test_scene();
  s.camera.width = 1920, s.camera.height = 1080;
  s.light.size = 0.5f;  // PCSS's penumbrae: a light of some size
  RenderRequest req = make_request(s, 2048, Product::kVisibility);
  req.filter = c.filter;
  engine().render(req);
  engine().render(req);
  std::map<std::string, double> per_pass;
  for (auto _ : state) {
    const RenderResult r = engine().render(req);
    double ms = 0.0;
    for (const PassTiming& t : r.timings) {
      if (t.pass.starts_with("visibility.") || t.pass.starts_with("csm.")) ms += t.device_ms;
      per_pass[t.pass + "_ms"] += t.device_ms;
    }
    state.SetIterationTime(ms / 1e3);
  }
  const double n = static_cast<double>(state.iterations());
  for (const auto& [name, ms] : per_pass) state.counters[name] = ms / n;
  state.SetLabel(c.name);
}

// Issue 42's full request: the forest's walker view, a 4096^2 map, 1080p, PCSS 16/32. The
// iteration time is the device time of every pass; each pass family is a counter.
void BM_FullRequest(benchmark::State& state) {
  const scenes::StandardScene forest = scenes::forest();
  const scenes::View& view = scenes::find_view(forest, "walker");
  RenderRequest req;
  req.scene = forest.scene;
  req.camera = view.camera;
  req.camera.width = 1920, req.camera.height = 1080;
  req.lights = {view.light};
  req.shadow_map.size = 4096;
  req.products = {Product::kVisibility};
  req.filter.kind = FilterKind::kPcss;
  engine().render(req);
  engine().render(req);
  std::map<std::string, double> per_family;
  double wall = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const RenderResult r = engine().render(req);
    wall += wall_ms_since(start);
    double ms = 0.0;
    for (const PassTiming& t : r.timings) {
      ms += t.device_ms;
      per_family[t.pass.substr(0, t.pass.find('.')) + "_ms"] += t.device_ms;
    }
    state.SetIterationTime(ms / 1e3);
  }
  const double n = static_cast<double>(state.iterations());
  for (const auto& [name, ms] : per_family) state.counters[name] = ms / n;
  state.counters["wall_ms"] = wall / n;
}

// The rasterizer on a device of its own, as raster_test drives it.
struct RasterDevice {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  Rasterizer rasterizer{runtime, kernels};
};

RasterDevice& raster_device() {
  static RasterDevice d;
  return d;
}

enum SceneId { kSphereCrowd = 0, kRandomField = 1 };

// One scene at a time lives on the device (and in the peer): the benches run scene by scene.
struct Loaded {
  int id = -1;
  bench::RasterScene scene;
  std::unique_ptr<SceneBuffers> buffers;
  std::vector<DrawItem> draws;
};

Loaded& load(int id) {
  static Loaded l;
  if (l.id == id) return l;
  l.buffers.reset();
  l.scene = id == kSphereCrowd ? bench::sphere_crowd() : bench::random_field(1000000);
  RasterDevice& d = raster_device();
  Timeline t;
  const Scene engine_scene = bench::one_instance(l.scene.mesh);
  l.buffers = std::make_unique<SceneBuffers>(d.runtime, d.kernels, engine_scene, t);
  l.draws = make_draws(engine_scene, *l.buffers, l.scene.world_to_ndc,
                       [](const Instance&) { return true; });
  l.id = id;
  return l;
}

struct RasterTime {
  double total = 0, setup = 0, bin = 0, raster = 0;
};

RasterTime rasterize(const Loaded& l, uint32_t size, const RasterPaths& paths,
                     std::vector<float>* depth = nullptr) {
  RasterDevice& d = raster_device();
  d.rasterizer.set_paths(paths);
  Timeline t;
  const RasterOutput& out =
      d.rasterizer.run(*l.buffers, l.draws, size, size, false, "map", "size", t);
  if (depth) {
    depth->resize(size_t{size} * size);
    d.runtime.read(out.depth, depth->data(), depth->size() * sizeof(float));
  }
  d.runtime.finish();
  RasterTime r;
  for (const PassTiming& p : t.timings()) {
    r.total += p.device_ms;
    if (p.pass == "map.setup") r.setup += p.device_ms;
    if (p.pass == "map.bin") r.bin += p.device_ms;
    if (p.pass == "map.raster") r.raster += p.device_ms;
  }
  return r;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Per-iteration figures by counter name; each counter reports its median.
struct Samples {
  std::map<std::string, std::vector<double>> by_name;
  void add(const std::string& name, double v) { by_name[name].push_back(v); }
  void add(const std::string& prefix, const RasterTime& t) {
    add(prefix + "ms", t.total);
    add(prefix + "setup_ms", t.setup);
    add(prefix + "bin_ms", t.bin);
    add(prefix + "raster_ms", t.raster);
  }
  double median_of(const std::string& name) const { return median(by_name.at(name)); }
  void report(benchmark::State& state) const {
    for (const auto& [name, v] : by_name) state.counters[name] = median(v);
  }
};

// The GL context and its one map and mesh, in this order so the peer goes before its context.
struct GlPeer {
  bench::EglContext context;
  std::unique_ptr<bench::DepthPeer> peer;
  int scene = -1;
  uint32_t size = 0;
};

// Made in main() so that its renderer heads the output; null (and why) where EGL failed.
std::unique_ptr<GlPeer> gl_peer;
std::string gl_peer_error;

void open_gl_peer() {
  setenv("LP_NUM_THREADS", "2", 0);  // llvmpipe on as many threads as PoCL has cores here
  try {
    gl_peer = std::make_unique<GlPeer>();
  } catch (const std::exception& e) {
    gl_peer_error = e.what();
  }
}

std::string gl_peer_context() {
  if (!gl_peer) return "none (" + gl_peer_error + ")";
  return gl_peer->context.platform() + " platform: " + gl_peer->context.description();
}

// The peer's map for `scene` at `size`, the mesh uploaded once (outside any timed draw).
bench::DepthPeer& peer(int scene, uint32_t size) {
  GlPeer& g = *gl_peer;
  if (!g.peer || g.size != size || g.scene != scene) {
    g.peer.reset();
    g.peer = std::make_unique<bench::DepthPeer>(size);
    g.peer->upload(load(scene).scene.mesh.positions, load(scene).scene.mesh.indices);
    g.scene = scene;
    g.size = size;
  }
  return *g.peer;
}

// Texels where the two depth maps differ by more than 1e-5 (a fill-rule or precision
// difference at an edge), as a fraction: shows the peer draws the same thing.
double mismatch(const std::vector<float>& a, const std::vector<float>& b) {
  size_t bad = 0;
  for (size_t i = 0; i < a.size(); ++i) bad += std::abs(a[i] - b[i]) > 1e-5f;
  return double(bad) / double(a.size());
}

void BM_VsGlPeer(benchmark::State& state) {
  if (!gl_peer) {
    state.SkipWithError(("no GL peer: " + gl_peer_error).c_str());
    return;
  }
  const int scene = static_cast<int>(state.range(0));
  const auto size = static_cast<uint32_t>(state.range(1));
  const Loaded& l = load(scene);
  bench::DepthPeer& gl = peer(scene, size);
  std::vector<float> ours_depth;
  rasterize(l, size, RasterPaths{}, &ours_depth);  // warm: buffers, program variant
  gl.draw(l.scene.world_to_ndc);
  state.counters["mismatch"] = mismatch(ours_depth, gl.depth());
  Samples samples;
  for (auto _ : state) {
    const RasterTime t = rasterize(l, size, RasterPaths{});
    const bench::DepthPeer::Timing g = gl.draw(l.scene.world_to_ndc);
    samples.add("gl_ms", g.wall_ms);
    samples.add("gl_gpu_ms", g.gpu_ms);
    samples.add("ours_", t);
    state.SetIterationTime(t.total / 1e3);
  }
  samples.report(state);
  state.SetLabel(gl_peer->context.renderer());
  state.counters["lead"] = samples.median_of("gl_ms") / samples.median_of("ours_ms");
  state.counters["gpu_lead"] = samples.median_of("gl_gpu_ms") / samples.median_of("ours_ms");
  state.counters["tris"] = double(l.scene.mesh.triangle_count());
}

// Path 0..4 (full tile, small32, point, hiz, vector set-up) switched against the defaults (hiz:
// on against off), 5: all off against the defaults, 6: counters by tile against by chunk.
void BM_RasterPath(benchmark::State& state) {
  const int scene = static_cast<int>(state.range(0));
  const auto size = static_cast<uint32_t>(state.range(1));
  const int path = static_cast<int>(state.range(2));
  const Loaded& l = load(scene);
  RasterPaths off;
  bool* flags[] = {&off.full_tile, &off.small32, &off.point, &off.hiz, &off.vector_setup};
  for (int k = 0; k < 5; ++k)
    if (path == k) *flags[k] = !*flags[k];
  if (path == 5) off = RasterPaths{false, false, false, false, false, false};  // every field
  if (path == 6) off.bin_by_chunk = false;
  rasterize(l, size, off);
  rasterize(l, size, RasterPaths{});
  Samples samples;
  for (auto _ : state) {
    const RasterTime ta = rasterize(l, size, off), tb = rasterize(l, size, RasterPaths{});
    samples.add("off_", ta);
    samples.add("on_", tb);
    state.SetIterationTime(tb.total / 1e3);
  }
  samples.report(state);
  state.counters["speedup"] = samples.median_of("off_ms") / samples.median_of("on_ms");
}

BENCHMARK(BM_VsGlPeer)
    ->ArgNames({"scene", "map"})
    ->ArgsProduct({{kSphereCrowd, kRandomField}, {1024, 2048, 4096, 8192}})
    ->Iterations(9)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RasterPath)
    ->ArgNames({"scene", "map", "off"})
    ->ArgsProduct({{kSphereCrowd, kRandomField}, {2048, 8192}, {0, 1, 2, 3, 4, 5, 6}})
    ->Iterations(7)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ShadowMapRaster)
    ->ArgNames({"tris", "map"})
    ->ArgsProduct({{10000, 100000, 1000000}, {1024, 2048, 4096}})
    ->MinTime(1.0)  // seconds of device time: several iterations even for the slow cases
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Filter1080p)
    ->ArgName("filter")
    ->DenseRange(0, 4)  // filter_cases(): hard, pcf2x2, poisson64, pcss16_32, csm8
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FullRequest)->UseManualTime()->Unit(benchmark::kMillisecond);
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
  shadow::bench::add_machine_context(shadow::raster_device().runtime.device_name());
  shadow::open_gl_peer();
  benchmark::AddCustomContext("gl_peer", shadow::gl_peer_context());
  benchmark::RunSpecifiedBenchmarks();
  shadow::gl_peer.reset();  // GL objects and context before the process's own teardown
  benchmark::Shutdown();
  return 0;
}
