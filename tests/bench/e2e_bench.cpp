// shadow-e2e-bench (issue 12, part 2): where the time goes between the device and the files, per
// product size. Starts the real server in-process and, per case, measures (medians of --reps):
//   device     the server's pass timings (sum), from an in-process render;
//   serialize  slicing the result into chunk messages and serializing them as gRPC does, per
//              chunk compression (none, zstd); wire bytes;
//   assemble   parsing those messages and assembling them, as the client does;
//   exr        writing the EXR of each product per compression (ms and file bytes); png: preview;
//   shadowctl  shadowctl's own pipelined path (render_to_files) over loopback: header, last chunk
//              and all files written, per chunk compression, with and without PNG previews.
//   process    with --shadowctl PATH: the shadowctl program as a user runs it, on the case's scene
//              written as an OBJ (a 640x360 view for the maps), default flags but the size and
//              products: its start-up (--help), the device time and the report's phases, and the
//              wall time from process start to exit (median of --reps after a warm-up).
//
//   shadow-e2e-bench [--reps 5] [--out /tmp/e2e-bench] [--shadowctl PATH] [--process-only]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <fstream>
#include <sstream>

#include <CLI/CLI.hpp>

#include "machine_context.hpp"
#include "oracle/standard_scenes.hpp"
#include "output/exr_writer.hpp"
#include "output/png_preview.hpp"
#include "scenes/demo_scene.hpp"
#include "service/server.hpp"
#include "shadowctl/render_to_files.hpp"
#include "wire/convert.hpp"
#include "wire/names.hpp"
#include "wire/result_assembler.hpp"
#include "wire/result_slicer.hpp"

namespace {

using namespace shadow;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Median wall time of `reps` calls of f.
double time_ms(int reps, const std::function<void()>& f) {
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = Clock::now();
    f();
    t.push_back(ms_since(t0));
  }
  return median(t);
}

struct Case {
  std::string name;
  RenderRequest request;
};

std::vector<Case> cases() {
  const scenes::StandardScene forest = scenes::forest();
  RenderRequest base;
  base.scene = forest.scene;
  base.camera = forest.views[0].camera;
  base.lights = {forest.views[0].light};
  base.lights[0].size = 0;
  std::vector<Case> out;
  for (uint32_t size : {1024u, 2048u, 4096u}) {
    RenderRequest r = base;
    r.shadow_map.size = size;
    r.products = {Product::kShadowMap};
    out.push_back({"forest shadowmap " + std::to_string(size) + "²", r});
  }
  RenderRequest vis = base;
  vis.shadow_map.size = 2048;
  vis.camera.width = 1920;
  vis.camera.height = 1080;
  vis.products = {Product::kVisibility};
  out.push_back({"forest visibility 1920x1080", vis});
  const scenes::DemoSetup d = scenes::demo_scene();
  RenderRequest demo;
  demo.scene = std::make_shared<Scene>(d.scene);
  demo.camera = d.camera;
  demo.lights = {d.light};
  demo.shadow_map = d.shadow_map;
  demo.shadow_map.size = 4096;
  demo.products = {Product::kShadowMap};
  out.push_back({"demo shadowmap 4096²", demo});
  return out;
}

double device_ms(const RenderResult& r) {
  double total = 0;
  for (const PassTiming& t : r.timings) total += t.device_ms;
  return total;
}

// The messages of a reply as the wire carries them.
std::vector<std::string> serialize(const RenderResult& r, ChunkCompression c) {
  std::vector<std::string> out;
  convert::stream_result(
      r, convert::kDefaultChunkBytes,
      [&](const v1::RenderResponse& m) {
        out.emplace_back();
        m.SerializeToString(&out.back());
        return true;
      },
      c);
  return out;
}

// The scene as an OBJ a user would hand shadowctl: each instance's triangles in world space, an
// object per instance.
void write_obj(const Scene& scene, const std::filesystem::path& file) {
  std::ofstream out(file);
  out.precision(9);
  size_t base = 1;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const Instance& inst = scene.instances[i];
    const Mesh& mesh = scene.meshes.at(inst.mesh);
    out << "o instance" << i << "\n";
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
      const float* p = &mesh.positions[3 * v];
      const glm::vec4 w = inst.transform * glm::vec4(p[0], p[1], p[2], 1.0f);
      out << "v " << w.x << ' ' << w.y << ' ' << w.z << "\n";
    }
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
      out << "f " << base + mesh.indices[t] << ' ' << base + mesh.indices[t + 1] << ' '
          << base + mesh.indices[t + 2] << "\n";
    base += mesh.vertex_count();
  }
}

// Runs the program; returns its wall ms from spawn to exit, and its stdout in `out`.
double run_ms(const std::vector<std::string>& argv, std::string* out) {
  const std::string capture = std::filesystem::temp_directory_path() / "e2e_bench_stdout.txt";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, capture.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const auto t0 = Clock::now();
  pid_t pid = 0;
  if (posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ) != 0)
    throw std::runtime_error("cannot start " + argv[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  const double ms = ms_since(t0);
  posix_spawn_file_actions_destroy(&actions);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(argv[0] + " failed (" + std::to_string(status) + ")");
  if (out) {
    std::stringstream text;
    text << std::ifstream(capture).rdbuf();
    *out = text.str();
  }
  return ms;
}

// The number after `label` on a line of shadowctl's report (its first), or NaN.
double report_ms(const std::string& report, const std::string& label) {
  std::istringstream lines(report);
  for (std::string line; std::getline(lines, line);) {
    const size_t at = line.find(label);
    if (at == std::string::npos || line.find_first_not_of(' ') != at) continue;
    std::istringstream rest(line.substr(at + label.size()));
    double v = NAN;
    if (rest >> v) return v;
  }
  return NAN;
}

// The process table: what a user of shadowctl waits for.
std::string process_table(const std::string& shadowctl, const std::string& address,
                          const std::filesystem::path& dir, int reps) {
  std::vector<double> startup;
  for (int i = 0; i <= reps; ++i) startup.push_back(run_ms({shadowctl, "--help"}, nullptr));
  startup.erase(startup.begin());
  std::string table =
      "| case | device | start-up | header | last chunk | written | process wall | wall - device "
      "|\n|---|---:|---:|---:|---:|---:|---:|---:|\n";
  const scenes::StandardScene forest = scenes::forest();
  const auto obj = dir / "forest.obj";
  write_obj(*forest.scene, obj);
  const Camera& cam = forest.views[0].camera;
  const Light& sun = forest.views[0].light;
  const auto vec = [](const glm::vec3& v) {
    char text[96];
    std::snprintf(text, sizeof text, "%.9g,%.9g,%.9g", v.x, v.y, v.z);
    return std::string(text);
  };
  struct Run {
    std::string name, size, map_size, products;
  };
  for (const Run& r : {Run{"forest shadowmap 1024²", "640x360", "1024", "shadowmap"},
                       Run{"forest shadowmap 4096²", "640x360", "4096", "shadowmap"},
                       Run{"forest shadowmap 8192²", "640x360", "8192", "shadowmap"},
                       Run{"forest visibility 1920x1080", "1920x1080", "2048", "visibility"}}) {
    const std::vector<std::string> argv = {shadowctl,    "render",
                                           "--server",   address,
                                           "--scene",    obj.string(),
                                           "--eye",      vec(cam.eye),
                                           "--target",   vec(cam.target),
                                           "--up",       vec(cam.up),
                                           "--fov",      std::to_string(cam.fov_deg),
                                           "--near",     std::to_string(cam.near),
                                           "--far",      std::to_string(cam.far),
                                           "--light",    "directional:" + vec(sun.direction),
                                           "--size",     r.size,
                                           "--map-size", r.map_size,
                                           "--products", r.products,
                                           "--out",      (dir / "process").string()};
    std::vector<double> wall, device, header, last, done;
    for (int i = 0; i <= reps; ++i) {
      std::string report;
      const double ms = run_ms(argv, &report);
      if (i == 0) continue;  // the warm-up
      wall.push_back(ms);
      device.push_back(report_ms(report, "total"));
      header.push_back(report_ms(report, "header (server queue, render, readback)"));
      last.push_back(report_ms(report, "last chunk"));
      done.push_back(report_ms(report, "all files written"));
    }
    char row[256];
    std::snprintf(row, sizeof row, "| %s | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |\n",
                  r.name.c_str(), median(device), median(startup), median(header), median(last),
                  median(done), median(wall), median(wall) - median(device));
    table += row;
    std::printf("%s", row);
    std::fflush(stdout);
  }
  return table;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"shadow-e2e-bench: the end-to-end split per product size"};
  int reps = 5;
  std::string out_dir = "/tmp/shadow-e2e-bench";
  app.add_option("--reps", reps, "repetitions per measurement (median)");
  app.add_option("--out", out_dir, "scratch directory for the files");
  std::string shadowctl;
  bool process_only = false;
  app.add_option("--shadowctl", shadowctl, "the shadowctl program: add the process table");
  app.add_flag("--process-only", process_only, "only the process table (needs --shadowctl)");
  CLI11_PARSE(app, argc, argv);

  service::tune_allocator();  // as shadow-server does
  service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  service::ShadowServer server(options);
  client::ShadowClient client(server.address());
  std::printf("machine: %s, %u threads; OpenCL: %s\n\n", bench::cpu_model().c_str(),
              std::thread::hardware_concurrency(), server.engine().device_name().c_str());

  if (!shadowctl.empty()) {
    std::filesystem::create_directories(out_dir);
    std::printf(
        "shadowctl as a process (ms; header, last chunk and written after the request "
        "was sent, wall from process start to exit):\n\n");
    const std::string table = process_table(shadowctl, server.address(), out_dir, reps);
    if (process_only) return 0;
    std::printf("\n");
  }
  std::printf(
      "| case | MiB | device | serialize none / zstd | wire MiB zstd | assemble none / zstd |"
      " png |\n|---|---:|---:|---:|---:|---:|---:|\n");
  std::string exr_table =
      "| case | none | rle | zips | zip | piz |\n|---|---:|---:|---:|---:|---:|\n";
  std::string ctl_table =
      "| case | device | chunks | preview | header | last chunk | EXR rows | all files | × device "
      "|\n|---|---:|---|---|---:|---:|---:|---:|---:|\n";
  for (const Case& c : cases()) {
    std::vector<double> device;
    RenderResult result;
    for (int i = 0; i < reps; ++i) {
      result = server.engine().render(c.request);
      device.push_back(device_ms(result));
    }
    const Texture& t = result.textures.at(0);
    const double mib = t.byte_size() / 1048576.0;
    double ser[2], asm_ms[2], wire_mib = 0;
    for (ChunkCompression comp : {ChunkCompression::kNone, ChunkCompression::kZstd}) {
      const int k = int(comp);
      ser[k] = time_ms(reps, [&] { serialize(result, comp); });
      const std::vector<std::string> wire = serialize(result, comp);
      if (comp == ChunkCompression::kZstd) {
        size_t bytes = 0;
        for (const std::string& m : wire) bytes += m.size();
        wire_mib = bytes / 1048576.0;
      }
      asm_ms[k] = time_ms(reps, [&] {
        convert::ResultAssembler a;
        v1::RenderResponse m;
        for (const std::string& s : wire) {
          m.ParseFromString(s);
          a.add(m);
        }
        a.finish();
      });
    }
    const auto dir = std::filesystem::path(out_dir);
    std::filesystem::create_directories(dir);
    const double png = time_ms(reps, [&] { output::write_png_preview(t, dir / "p.png"); });
    std::printf("| %s | %.0f | %.1f | %.1f / %.1f | %.1f | %.1f / %.1f | %.0f |\n", c.name.c_str(),
                mib, median(device), ser[0], ser[1], wire_mib, asm_ms[0], asm_ms[1], png);
    std::fflush(stdout);

    exr_table += "| " + c.name + " |";
    for (std::string_view comp : output::kExrCompressions) {
      const auto file = dir / ("t_" + std::string(comp) + ".exr");
      const double ms = time_ms(reps, [&] { output::write_exr(t, file, comp); });
      char cell[64];
      std::snprintf(cell, sizeof cell, " %.0f ms, %.1f MiB |", ms,
                    std::filesystem::file_size(file) / 1048576.0);
      exr_table += cell;
    }
    exr_table += "\n";

    for (ChunkCompression comp : {ChunkCompression::kNone, ChunkCompression::kZstd}) {
      for (bool preview : {false, true}) {
        v1::RenderRequest proto = convert::to_proto(c.request);
        proto.set_chunk_compression(names::kChunkCompressions.to_proto(comp));
        output::OutputOptions o;
        o.preview = preview ? output::Preview::kPng : output::Preview::kNone;
        std::vector<double> header, last, rows, done;
        for (int i = 0; i < reps; ++i) {
          const ctl::RenderedFiles f = ctl::render_to_files(client, proto, dir / "ctl", o);
          header.push_back(f.timeline.header);
          last.push_back(f.timeline.last_chunk);
          rows.push_back(f.timeline.exr_rows);
          done.push_back(f.timeline.done);
        }
        char row[512];
        std::snprintf(row, sizeof row,
                      "| %s | %.1f | %s | %s | %.1f | %.1f | %.1f | %.1f | %.1f |\n",
                      c.name.c_str(), median(device),
                      std::string(names::kChunkCompressions.name(comp)).c_str(),
                      preview ? "png" : "none", median(header), median(last), median(rows),
                      median(done), median(done) / median(device));
        ctl_table += row;
      }
    }
  }
  std::printf(
      "\nEXR writing (%s threads), ms and file size:\n\n%s\nshadowctl (ms after the "
      "request was sent):\n\n%s",
      "OpenEXR's pool, one per core", exr_table.c_str(), ctl_table.c_str());
  return 0;
}
