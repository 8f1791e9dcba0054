// shadow-e2e-bench (issue 12, part 2): where the time goes between the device and the files, per
// product size. Starts the real server in-process and, per case, measures (medians of --reps):
//   device     the server's pass timings (sum), from an in-process render;
//   serialize  slicing the result into chunk messages and serializing them as gRPC does, per
//              chunk compression (none, zstd); wire bytes;
//   assemble   parsing those messages and assembling them, as the client does;
//   exr        writing the EXR of each product per compression (ms and file bytes); png: preview;
//   shadowctl  shadowctl's own pipelined path (render_to_files) over loopback: header, last chunk
//              and all files written, per chunk compression, with and without PNG previews.
//
//   shadow-e2e-bench [--reps 5] [--out /tmp/e2e-bench]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"shadow-e2e-bench: the end-to-end split per product size"};
  int reps = 5;
  std::string out_dir = "/tmp/shadow-e2e-bench";
  app.add_option("--reps", reps, "repetitions per measurement (median)");
  app.add_option("--out", out_dir, "scratch directory for the files");
  CLI11_PARSE(app, argc, argv);

  service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  service::ShadowServer server(options);
  client::ShadowClient client(server.address());
  std::printf("machine: %s, %u threads; OpenCL: %s\n\n", bench::cpu_model().c_str(),
              std::thread::hardware_concurrency(), server.engine().device_name().c_str());

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
        o.png_preview = preview;
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
      "OIIO default", exr_table.c_str(), ctl_table.c_str());
  return 0;
}
