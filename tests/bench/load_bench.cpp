// shadow-load: N clients render the same request against a running shadow-server for a fixed
// time, through the real client library; prints renders/s, p50/p99 latency and the server's
// resident memory (current and peak, from /proc/PID/status). Mixed load adds one client that
// renders an 8192^2 map with a 1080p camera over and over beside the small clients.
//
//   shadow-load --server 127.0.0.1:50051 --server-pid PID --clients 4 --request small --seconds 20
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "scenes/demo_scene.hpp"
#include "scenes/shapes.hpp"
#include "service/convert.hpp"
#include "shadow_client.hpp"

namespace {

using namespace shadow;
using Clock = std::chrono::steady_clock;

// The demo scene, 1024^2, 640x360 visibility.
RenderRequest small_request() {
  const scenes::DemoSetup d = scenes::demo_scene();
  RenderRequest r;
  r.scene = std::make_shared<Scene>(d.scene);
  r.camera = d.camera;
  r.camera.width = 640;
  r.camera.height = 360;
  r.light = d.light;
  r.shadow_map = d.shadow_map;
  r.shadow_map.size = 1024;
  r.products = {Product::kVisibility};
  return r;
}

// 10^6 triangles (the demo with a finely cut ground), 4096^2, 1920x1080 visibility.
RenderRequest large_request() {
  RenderRequest r = small_request();
  auto scene = std::make_shared<Scene>(*r.scene);
  scene->meshes[0] = scenes::make_grid(40.0f, 708);
  r.scene = scene;
  r.shadow_map.size = 4096;
  r.camera.width = 1920;
  r.camera.height = 1080;
  return r;
}

// The mixed load's big one: an 8192^2 map and a 1080p camera.
RenderRequest huge_request() {
  RenderRequest r = small_request();
  r.shadow_map.size = 8192;
  r.camera.width = 1920;
  r.camera.height = 1080;
  return r;
}

// kB of VmRSS and VmHWM of `pid` (0, 0 when unknown).
std::pair<long, long> rss_kb(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  long value = 0, rss = 0, hwm = 0;
  while (in >> key) {
    if (key == "VmRSS:" && in >> value) rss = value;
    if (key == "VmHWM:" && in >> value) hwm = value;
  }
  return {rss, hwm};
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(p * v.size()))];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"shadow-load: concurrent clients against a running shadow-server"};
  std::string server, request = "small";
  int pid = 0, clients = 1;
  double seconds = 20;
  bool mixed = false;
  app.add_option("--server", server, "address of a running shadow-server")->required();
  app.add_option("--server-pid", pid, "its process id, for resident memory");
  app.add_option("--clients", clients, "concurrent clients")->check(CLI::Range(1, 64));
  app.add_option("--request", request, "small or large")->check(CLI::IsMember({"small", "large"}));
  app.add_option("--seconds", seconds, "how long to send");
  app.add_flag("--mixed", mixed, "one more client renders 8192^2 maps all along");
  CLI11_PARSE(app, argc, argv);

  const v1::RenderRequest proto =
      convert::to_proto(request == "small" ? small_request() : large_request());
  const v1::RenderRequest huge = convert::to_proto(huge_request());
  std::mutex mutex;
  std::vector<double> latencies, huge_latencies;
  std::atomic<long> errors{0};
  long peak_rss = 0;
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  std::atomic<bool> running{true};
  std::thread sampler([&] {
    while (running) {
      peak_rss = std::max(peak_rss, rss_kb(pid).first);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  const auto client_loop = [&](const v1::RenderRequest& req, std::vector<double>& out) {
    client::ShadowClient client(server);
    while (Clock::now() < end) {
      const auto t0 = Clock::now();
      try {
        client.render(req, std::chrono::minutes(2));
      } catch (const std::exception& e) {
        if (errors++ < 3) std::fprintf(stderr, "error: %s\n", e.what());
        continue;
      }
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      std::lock_guard<std::mutex> lock(mutex);
      out.push_back(ms);
    }
  };
  const auto t0 = Clock::now();
  std::vector<std::thread> threads;
  for (int i = 0; i < clients; ++i) threads.emplace_back([&] { client_loop(proto, latencies); });
  if (mixed) threads.emplace_back([&] { client_loop(huge, huge_latencies); });
  for (std::thread& t : threads) t.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  running = false;
  sampler.join();
  const auto [rss, hwm] = rss_kb(pid);
  std::printf(
      "%s x%d%s: %.1f renders/s, p50 %.0f ms, p99 %.0f ms, %zu renders, %ld errors; server RSS "
      "%.0f MiB now, peak %.0f MiB sampled (VmHWM %.0f MiB)",
      request.c_str(), clients, mixed ? " + 8192^2" : "", latencies.size() / elapsed,
      percentile(latencies, 0.5), percentile(latencies, 0.99), latencies.size(), errors.load(),
      rss / 1024.0, peak_rss / 1024.0, hwm / 1024.0);
  if (mixed)
    std::printf("; 8192^2: %zu renders, p50 %.0f ms", huge_latencies.size(),
                percentile(huge_latencies, 0.5));
  std::printf("\n");
  return errors > 0 ? 1 : 0;
}
