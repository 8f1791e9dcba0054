// shadow-load: N clients render the same request against a running shadow-server for a fixed
// time, through the real client library; prints renders/s, p50/p99 latency and the server's
// resident memory (current and peak, from /proc/PID/status). Mixed load adds one client that
// renders an 8192^2 map with a 1080p camera over and over beside the small clients.
//
//   shadow-load --server 127.0.0.1:50051 --server-pid PID --clients 4 --request small --seconds 20
//
// --samples FILE writes the server's CPU use and RSS every 50 ms (t_s, cpu_percent, rss_mib);
// --once --deadline-ms D sends one request per client with a deadline, for cancellation timing.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "scenes/demo_scene.hpp"
#include "scenes/shapes.hpp"
#include "shadow_client.hpp"
#include "wire/convert.hpp"

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
  r.lights = {d.light};
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

// The mixed load's big one, or with --once a PCSS-64/64 one that runs for seconds: 8192^2 and 8K.
RenderRequest pcss_request() {
  RenderRequest r = huge_request();
  r.camera.width = 7680;
  r.camera.height = 4320;
  r.lights[0].size = 1.0f;
  r.filter.kind = FilterKind::kPcss;
  r.filter.pcss.blocker_samples = r.filter.pcss.filter_samples = 64;
  return r;
}

// Seconds of CPU (user + system) `pid` has used.
double cpu_seconds(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string field;
  double ticks = 0;
  for (int i = 1; i <= 15 && in >> field; ++i)
    if (i == 14 || i == 15) ticks += std::stod(field);  // utime, stime (no spaces in comm here)
  return ticks / double(sysconf(_SC_CLK_TCK));
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
  bool mixed = false, once = false;
  int deadline_ms = 120000;
  std::string samples_path;
  int scene_mib = 0;
  app.add_option("--server", server, "address of a running shadow-server")->required();
  app.add_option("--server-pid", pid, "its process id, for resident memory");
  app.add_option("--clients", clients, "concurrent clients")->check(CLI::Range(1, 64));
  app.add_option("--request", request, "small, large or pcss (8192^2 map, 8K camera, PCSS 64/64)")
      ->check(CLI::IsMember({"small", "large", "pcss"}));
  app.add_flag("--once", once, "each client sends one request");
  app.add_option("--deadline-ms", deadline_ms, "each request's deadline");
  app.add_option("--samples", samples_path, "CSV of the server's CPU and RSS every 50 ms");
  app.add_option("--scene-mib", scene_mib,
                 "add a mesh of this many MiB of vertices that no instance draws (large requests "
                 "that cost little to render, for the memory budget)");
  app.add_option("--seconds", seconds, "how long to send");
  app.add_flag("--mixed", mixed, "one more client renders 8192^2 maps all along");
  CLI11_PARSE(app, argc, argv);

  v1::RenderRequest proto = convert::to_proto(request == "small"   ? small_request()
                                              : request == "large" ? large_request()
                                                                   : pcss_request());
  if (scene_mib > 0) {
    Mesh ballast;  // one triangle's corners over and over: valid, drawn by no instance
    const size_t vertices = (size_t(scene_mib) << 20) / 12;
    ballast.positions.assign(3 * vertices, 0.0f);
    ballast.indices = {0, 1, 2};
    *proto.mutable_scene()->add_meshes() = convert::to_proto(ballast);
  }
  const v1::RenderRequest huge = convert::to_proto(huge_request());
  std::mutex mutex;
  std::vector<double> latencies, huge_latencies;
  std::atomic<long> errors{0};
  long peak_rss = 0;
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  std::atomic<bool> running{true};
  const auto start = Clock::now();
  std::thread sampler([&] {
    std::ofstream csv;
    if (!samples_path.empty()) csv.open(samples_path), csv << "t_s,cpu_percent,rss_mib\n";
    double last_cpu = cpu_seconds(pid);
    auto last = Clock::now();
    while (running) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      const long rss = rss_kb(pid).first;
      peak_rss = std::max(peak_rss, rss);
      const auto now = Clock::now();
      const double cpu = cpu_seconds(pid);
      if (csv)
        csv << std::chrono::duration<double>(now - start).count() << ','
            << 100.0 * (cpu - last_cpu) / std::chrono::duration<double>(now - last).count() << ','
            << rss / 1024.0 << '\n';
      last_cpu = cpu, last = now;
    }
  });
  const auto client_loop = [&](const v1::RenderRequest& req, std::vector<double>& out) {
    client::ShadowClient client(server);
    for (bool first = true; first || (!once && Clock::now() < end); first = false) {
      const auto t0 = Clock::now();
      try {
        client.render(req, std::chrono::milliseconds(deadline_ms));
      } catch (const client::RpcError& e) {
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        if (errors++ < 3) std::fprintf(stderr, "after %.0f ms: %s\n", ms, e.what());
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
  // With --once, watch the server settle for the rest of --seconds.
  if (once) std::this_thread::sleep_until(end);
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
