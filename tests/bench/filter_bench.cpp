// shadow-filter-bench: the filter passes on textures already on the device, timed by their
// OpenCL profiling events. Each figure is printed next to its floor or target as counters.
#include <map>
#include <random>
#include <string>

#include <benchmark/benchmark.h>

#include "machine_context.hpp"
#include "stream_bandwidth.hpp"

#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/pcf.hpp"
#include "engine/passes/summed_area.hpp"

namespace shadow {
namespace {

struct Device {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  MipPyramidPass mips{runtime, kernels};
  SummedAreaPass sat{runtime, kernels};
  PcfPass pcf{runtime, kernels};
  cl::Buffer input;
};

Device& device() {
  static Device d;
  return d;
}

DeviceTexture random_texture(uint32_t size) {
  Device& d = device();
  std::vector<float> v(size_t{size} * size);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float& x : v) x = u(rng);
  d.runtime.ensure(d.input, v.size() * sizeof(float));
  d.runtime.write(d.input, v.data(), v.size() * sizeof(float));
  d.runtime.finish();
  return {&d.input, size, size, 1};
}

template <typename Run>
void time_device(benchmark::State& state, Run run) {
  Timeline warm;
  run(warm);  // first use allocates and compiles
  std::map<std::string, double> per_pass;
  for (auto _ : state) {
    Timeline t;
    run(t);
    device().runtime.finish();
    double ms = 0;
    for (const PassTiming& p : t.timings()) {
      ms += p.device_ms;
      per_pass[p.pass + "_ms"] += p.device_ms;
    }
    state.SetIterationTime(ms / 1e3);
  }
  for (const auto& [name, ms] : per_pass) state.counters[name] = ms / double(state.iterations());
}

// Bytes moved at ~20 GB/s (2-thread copy on this machine): a float SAT reads 4 and writes 4 bytes
// per texel (~7 ms at 4096^2); this double table reads the input twice and writes 8.
void BM_SummedAreaTable(benchmark::State& state) {
  const auto size = static_cast<uint32_t>(state.range(0));
  const DeviceTexture tex = random_texture(size);
  time_device(state, [&](Timeline& t) { device().sat.run(tex, "sat", t); });
  const double texels = double(size) * size;
  state.counters["float_floor_ms"] = texels * 8 / 20e9 * 1e3;
  state.counters["own_floor_ms"] = texels * 16 / 20e9 * 1e3;
  state.counters["target_ms"] = 2 * 7.0 * texels / (4096.0 * 4096.0);
}

void BM_MipPyramid(benchmark::State& state) {
  const auto size = static_cast<uint32_t>(state.range(0));
  const DeviceTexture tex = random_texture(size);
  time_device(state, [&](Timeline& t) { device().mips.run(tex, "mips", t); });
  state.counters["floor_ms"] = double(size) * size * 4 * (1 + 1.0 / 3) / 20e9 * 1e3;
  state.counters["target_ms"] = 10.0 * double(size) * size / (4096.0 * 4096.0);
}

// N-tap Poisson PCF over a camera image of receivers on one tilted plane (every pixel does the
// full filter) against a 2048^2 map of random depths. Target: 64 taps at 1920x1080 <= 60 ms.
void BM_PoissonPcf(benchmark::State& state) {
  const auto taps = static_cast<uint32_t>(state.range(0));
  const uint32_t w = 1920, h = 1080, pixels = w * h, map_size = 2048;
  Device& d = device();
  std::vector<float> pos, nrm, depth(size_t{map_size} * map_size);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0.3f, 1.0f);
  for (float& z : depth) z = u(rng);
  for (uint32_t p = 0; p < pixels; ++p) {
    const float x = (p % w + 0.5f) / w, y = (p / w + 0.5f) / h;
    pos.insert(pos.end(), {x, y, 0.5f + 0.1f * x});
    nrm.insert(nrm.end(), {-0.0995f, 0.0f, 0.995f, 1.0f});
  }
  GBuffer g{d.runtime.upload(pos), d.runtime.upload(nrm)};
  const cl::Buffer map = d.runtime.upload(depth);
  d.runtime.finish();
  ShadowMapSettings settings;
  settings.size = map_size;
  const PcfParams params{PcfParams::Mode::kPoisson, taps, 3.0f, true};
  // The light along -z, facing the plane: the default light travels along -y, edge-on to the
  // plane, and its pixels took the facing-away exit instead of the filter.
  Light light;
  light.direction = {0.0f, 0.0f, -1.0f};
  time_device(state, [&](Timeline& t) {
    d.pcf.run(g, pixels, w, {{ViewSetup{}, &map}}, light, settings, params, t);
  });
  state.counters["target_ms"] = 60.0 * taps / 64;
  // Memory floor: position, normal in, visibility out (12 + 16 + 4 bytes a pixel); the taps'
  // map texels come from cache (a 2048^2 map is 16 MiB, the taps of a strip are close).
  state.counters["floor_ms"] = bench::floor_ms(32.0 * pixels);
  state.counters["stream_GBps"] = bench::stream_bytes_per_s() / 1e9;
}

BENCHMARK(BM_SummedAreaTable)
    ->ArgName("size")
    ->Arg(4096)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MipPyramid)
    ->ArgName("size")
    ->Arg(4096)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PoissonPcf)
    ->ArgName("taps")
    ->Arg(1)  // the per-pixel set-up alone
    ->Arg(16)
    ->Arg(64)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace shadow

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  shadow::bench::add_machine_context(shadow::device().runtime.device_name());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
