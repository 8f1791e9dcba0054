// shadow-bench: every request variant on every standard scene view, timed through a real gRPC
// server (and the same engine in-process, to show the transport's cost) and scored against the
// Embree oracle. Writes results.md, results.csv (one row per case) and variants.csv (one row per
// variant: its means and whether it is on the Pareto front), and goal_ceiling.csv (the error
// goals replayed with better predictions, goal_ceiling.hpp); scripts/plot_bench.py draws the
// plots from the CSV files (scripts/bench-shadow runs both). On a terminal it shows each
// case and its progress (done/total, elapsed, ETA); otherwise (CI) only errors and the summary.
//
// Variants are fragments of a shadow.v1.RenderRequest in protobuf's JSON mapping, merged onto
// the base request: any option the proto gains (filters, PSM, cube faces...) is benchmarked by
// adding a row to the table or passing --variant NAME='{"shadowMap":{...}}', with no code here.
// A variant the server rejects for a view (e.g. TECHNIQUE_CUBE with a sun) is skipped there.
//
// Equal texels (issues 5 and 17): "uniform 2048", "psm 2048", "lispsm 2048" and "psm_cube 912"
// (PSM's cube-map approach, 912^2 texels per face: 5 faces = 4.16 M, about 2048^2 = 4.19 M) are
// compared at about equal total texel count on every view, overall and near the viewer, in a
// section of results.md of their own with the maps the server drew and their texels in all (the
// face count depends on the light). Every case also reports map_faces and map_texels
// (results.csv, and a column of the cases table). Those variants and AUTO, the fixed
// configurations and the error goals also run on four nudged frames per view (frames.hpp),
// written to frames.csv, for AUTO's comparison and the goals' judgement over frames.
#include <google/protobuf/util/json_util.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "calibration_counts.hpp"
#include "case.hpp"
#include "edge_estimate.hpp"
#include "engine/choose/auto_pick.hpp"  // faces_light
#include "engine/choose/calibration.hpp"
#include "engine/choose/quality_pick.hpp"
#include "equal_texels.hpp"
#include "frames.hpp"
#include "goal_ceiling.hpp"
#include "goal_predictions.hpp"
#include "oracle/area_light.hpp"
#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/standard_scenes.hpp"
#include "oracle/texel_density.hpp"
#include "pareto.hpp"
#include "quality_section.hpp"
#include "service/server.hpp"
#include "shadow_client.hpp"
#include "wire/convert.hpp"
#include "wire/names.hpp"

namespace shadow::bench {
namespace {

struct Variant {
  std::string name;
  std::string json;   // merged onto the base request
  bool soft = false;  // scored against area-light visibility instead of hard shadow rays
  // Ping-pong blur: receiver class 0 on instance 0, which is the ground in every standard scene.
  bool ground_class = false;
};

// The default sweep: map resolution, bias and filters, today's request options.
std::vector<Variant> default_variants(bool full) {
  std::vector<Variant> v;
  // "name size": {"shadowMap":{"technique":"TECHNIQUE_X","size":size}} for each size.
  const auto technique = [&](const std::string& name, const char* proto, std::vector<int> sizes) {
    for (int s : sizes)
      v.push_back({name + " " + std::to_string(s), R"({"shadowMap":{"technique":")" +
                                                       std::string(proto) + R"(","size":)" +
                                                       std::to_string(s) + "}}"});
  };
  // 512 first: the quality goals' probe map (kQualityProbeSize), which --calibration needs
  // before the other variants of a view.
  technique("uniform", "TECHNIQUE_UNIFORM",
            full ? std::vector<int>{512, 1024, 2048, 4096, 8192}
                 : std::vector<int>{512, 1024, 2048, 4096});
  // Point lights (the room's views; other views reject them and are skipped). The variants
  // below without a technique render cubes there too.
  technique("cube", "TECHNIQUE_CUBE", {1024, 2048});
  v.push_back({"uniform 2048 no slope bias", R"({"shadowMap":{"size":2048,"biasSlope":0}})"});
  // The slope bias's default before 2026-11-27 (issue 17), which leaked light where light grazes.
  v.push_back({"uniform 2048 slope 1.5", R"({"shadowMap":{"size":2048,"biasSlope":1.5}})"});
  // Perspective shadow maps (directional views only: spot views are rejected and skipped).
  // Every size a quality goal may pick (kQualitySizes), so its pick is judged against the same
  // configuration run on its own.
  technique("psm", "TECHNIQUE_PSM", {512, 1024, 2048, 4096});
  // PSM's cube-map approach at about uniform 2048's total texels (see equal_texels.hpp).
  technique("psm_cube", "TECHNIQUE_PSM_CUBE", {kPsmCubeFaceSize});
  // Light Space Perspective Shadow Maps (directional views only: others are rejected, skipped).
  technique("lispsm", "TECHNIQUE_LISPSM", {512, 1024, 2048, 4096});
  // The server's own pick (TECHNIQUE_AUTO) at the same sizes.
  technique("auto", "TECHNIQUE_AUTO", {1024, 2048});
  // Quality goals (the server picks technique and size, RenderHeader.quality): misclassified
  // shares and device-time budgets.
  for (const char* e : {"0.005", "0.01", "0.02"})
    v.push_back(
        {std::string("quality error ") + std::to_string(std::stod(e) * 100).substr(0, 3) + "%",
         std::string(R"({"quality":{"maxError":)") + e + "}}"});
  for (const char* ms : {"20", "60"})
    v.push_back({std::string("quality ") + ms + " ms",
                 std::string(R"({"quality":{"maxDeviceMs":)") + ms + "}}"});
  // Filters anti-alias the hard shadow, so they are scored against hard shadow rays.
  v.push_back({"pcf2x2 2048", R"({"shadowMap":{"size":2048},"filter":{"pcf2x2":{}}})"});
  v.push_back({"poisson 16 r2 2048",
               R"({"shadowMap":{"size":2048},"filter":{"poisson":{"taps":16,"radius":2}}})"});
  v.push_back({"poisson 16 r2 1024",
               R"({"shadowMap":{"size":1024},"filter":{"poisson":{"taps":16,"radius":2}}})"});
  // PCSS softens by the light's size (each view's light carries one: suns 0.5-2 degrees, spots a
  // few cm), so it is scored against area-light visibility.
  v.push_back({"pcss 16/32 2048", R"({"shadowMap":{"size":2048},"filter":{"pcss":{}}})", true});
  // PCSS-CSM: the blocker average from the CSM basis instead of PCSS's blocker search, at
  // M = 4, 8, 16 in float32 and float16 (area light); CSM's prefiltered test over 4 texels is a
  // hard-shadow anti-aliasing filter like PCF (hard rays).
  for (int m : {4, 8, 16})
    for (const char* storage : {"FLOAT32", "FLOAT16"}) {
      const std::string lower = storage == std::string("FLOAT32") ? "float32" : "float16";
      v.push_back({"pcss_csm M" + std::to_string(m) + " " + lower + " 2048",
                   R"({"shadowMap":{"size":2048},"filter":{"pcssCsm":{"terms":)" +
                       std::to_string(m) + R"(,"storage":"CSM_STORAGE_)" + storage + R"("}}})",
                   true});
    }
  // The SAT lookup (a box of exactly the window, float64 tables) beside the mips' trilinear one.
  v.push_back(
      {"pcss_csm M8 float32 sat 2048",
       R"({"shadowMap":{"size":2048},"filter":{"pcssCsm":{"terms":8,"lookup":"CSM_LOOKUP_SAT"}}})",
       true});
  v.push_back(
      {"csm M8 w4 2048", R"({"shadowMap":{"size":2048},"filter":{"csm":{"terms":8,"window":4}}})"});
  v.push_back(
      {"csm M8 w4 sat 2048",
       R"({"shadowMap":{"size":2048},"filter":{"csm":{"terms":8,"window":4,"lookup":"CSM_LOOKUP_SAT"}}})"});
  // CSM on the warped maps: each technique's own basis.
  for (const char* t : {"PSM", "LISPSM"})
    v.push_back({std::string("csm M8 w4 ") + (t == std::string("PSM") ? "psm" : "lispsm") + " 2048",
                 std::string(R"({"shadowMap":{"size":2048,"technique":"TECHNIQUE_)") + t +
                     R"("},"filter":{"csm":{"terms":8,"window":4}}})"});
  // Blur softens the ground's shadows only (Kozlov 14.4.2); scored against the area light too.
  v.push_back(
      {"blur r4x2 2048 ground", R"({"shadowMap":{"size":2048},"filter":{"blur":{}}})", true, true});
  if (full) {
    v.push_back(
        {"uniform 2048 no bias", R"({"shadowMap":{"size":2048,"biasSlope":0,"biasConstant":0}})"});
    v.push_back({"uniform 2048 slope 0.5", R"({"shadowMap":{"size":2048,"biasSlope":0.5}})"});
    v.push_back({"psm 1024 slide-back", R"({"shadowMap":{"technique":"TECHNIQUE_PSM","size":1024,)"
                                        R"("psmCasters":"PSM_CASTERS_SLIDE_BACK"}})"});
    v.push_back({"poisson 64 r3 2048",
                 R"({"shadowMap":{"size":2048},"filter":{"poisson":{"taps":64,"radius":3}}})"});
    v.push_back({"uniform 2048 slope 4",
                 R"({"shadowMap":{"size":2048,"biasSlope":4,"biasConstant":1e-4}})"});
  }
  return v;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The variants --calibration runs and counts: the hard test at default biases, no goal.
bool calibrates(const Variant& v) {
  return !v.soft && v.json.find("filter") == std::string::npos &&
         v.json.find("bias") == std::string::npos && v.json.find("quality") == std::string::npos;
}

const Texture* find(const RenderResult& r, Product p) {
  for (const Texture& t : r.textures)
    if (t.kind == p) return &t;
  return nullptr;
}

}  // namespace
}  // namespace shadow::bench

int main(int argc, char** argv) {
  using namespace shadow;
  using namespace shadow::bench;
  CLI::App app{"shadow-bench: speed vs accuracy of every request variant on the standard scenes"};
  std::string server_address, out_dir = "bench-out", only_scene, only_variants;
  bool full = false, no_in_process = false;
  int runs = 0, width = 0;
  std::vector<std::string> extra, extra_soft;
  std::string calibration_out;
  app.add_option("--server", server_address, "use this server instead of starting one");
  app.add_option("--out", out_dir, "output directory");
  app.add_flag("--full", full, "the long sweep: more sizes and biases, 1280x720, 7 runs");
  app.add_option("--runs", runs, "timed runs per case after one warm-up (default 5, --full 7)");
  app.add_option("--width", width, "camera width (height keeps 16:9)");
  app.add_option("--scene", only_scene, "only this standard scene");
  app.add_option("--variants-matching", only_variants,
                 "only the variants whose name contains this text, or one of several separated "
                 "by | (e.g. pcss, or 'uniform|quality')");
  app.add_flag("--no-in-process", no_in_process, "skip the in-process engine timing");
  app.add_option("--variant", extra, "NAME=JSON: an extra RenderRequest fragment (repeatable)");
  app.add_option("--soft-variant", extra_soft,
                 "NAME=JSON: as --variant, scored against area-light visibility");
  app.add_option("--calibration", calibration_out,
                 "write the quality goal's calibration table here (data/calibration.csv) from "
                 "the hard-test variants, and run only those");
  CLI11_PARSE(app, argc, argv);
  if (runs <= 0) runs = full ? 7 : 5;
  if (width <= 0) width = full ? 1280 : 640;

  std::vector<Variant> variants = default_variants(full);
  for (const auto& [list, soft] : {std::pair{&extra, false}, {&extra_soft, true}})
    for (const std::string& e : *list) {
      const auto eq = e.find('=');
      if (eq == std::string::npos) {
        std::fprintf(stderr, "--variant wants NAME=JSON, got %s\n", e.c_str());
        return 2;
      }
      variants.push_back({e.substr(0, eq), e.substr(eq + 1), soft});
    }
  if (!only_variants.empty())
    std::erase_if(variants, [&](const Variant& v) {
      std::stringstream texts(only_variants);
      for (std::string t; std::getline(texts, t, '|');)
        if (v.name.find(t) != std::string::npos) return false;
      return true;
    });
  CalibrationCounts calibration;
  if (!calibration_out.empty()) {
    std::erase_if(variants, [](const Variant& v) { return !calibrates(v); });
    if (variants.empty() || variants.front().name != probe_variant()) {
      std::fprintf(stderr, "--calibration needs the variant \"%s\" first (the probe's map)\n",
                   probe_variant().c_str());
      return 2;
    }
  }

  std::unique_ptr<service::ShadowServer> own;
  if (server_address.empty() || !no_in_process) {
    service::ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.engine.profile = true;
    own = std::make_unique<service::ShadowServer>(options);
    if (server_address.empty()) server_address = own->address();
  }
  client::ShadowClient client(server_address);
  if (isatty(fileno(stderr))) std::fprintf(stderr, "server %s\n", server_address.c_str());

  std::vector<scenes::StandardScene> all_scenes = scenes::standard_scenes();
  std::erase_if(all_scenes,
                [&](const auto& sc) { return !only_scene.empty() && sc.name != only_scene; });
  size_t total = 0, done = 0;  // cases
  for (const scenes::StandardScene& sc : all_scenes) total += sc.views.size() * variants.size();
  const size_t total_runs = total * size_t(runs);
  size_t done_runs = 0;  // timed runs, and those a refused case would have had
  const bool terminal = isatty(fileno(stderr)) != 0;
  const auto started = std::chrono::steady_clock::now();
  // On a terminal: "[ 12/300 cases] 0:41 elapsed, ETA 16:05" rewritten in place under the case
  // lines; the ETA counts timed runs, which finish round by round.
  const auto progress = [&] {
    if (!terminal) return;
    const double s = ms_since(started) / 1e3;
    const double eta = done_runs ? s * double(total_runs - done_runs) / double(done_runs) : 0.0;
    std::fprintf(stderr, "\r[%3zu/%zu cases] %d:%02d elapsed, ETA %d:%02d ", done, total,
                 int(s) / 60, int(s) % 60, int(eta) / 60, int(eta) % 60);
  };
  std::vector<Case> cases;
  std::vector<FrameError> frames;  // the nudged frames (frames.hpp)
  for (const scenes::StandardScene& sc : all_scenes) {
    oracle::RayOracle oracle(*sc.scene);
    const v1::Scene scene_proto = convert::to_proto(*sc.scene);
    for (const scenes::View& view : sc.views) {
      const Camera cam = bench_camera(view, width);
      std::vector<float> hard, soft;
      double hard_boundary = 0, soft_boundary = 0;  // their boundary shares, once cast
      // Per pixel, the probe's boundary share in its cell of the goals' sample grid, once the
      // probe's variant has run.
      std::vector<float> probe_boundary;
      // Eye distance per pixel (NaN where nothing is seen), for the error by distance.
      std::vector<double> distance;
      // Whether each pixel's seen side faces the light (what the calibration counts).
      std::vector<uint8_t> lit_side;
      oracle::ViewSurface surface;  // where a map's shadow edges lie (oracle::boundary_share)
      {
        const oracle::CameraHits hits = oracle.cast_camera(cam);
        surface = oracle::view_surface(hits, *sc.scene, cam, view.light);
        distance.resize(hits.size());
        lit_side.resize(hits.size());
        for (size_t i = 0; i < hits.size(); ++i) {
          distance[i] = glm::length(hits.position[i] - glm::dvec3(cam.eye));
          lit_side[i] = hits.hit(i) && faces_light(view.light, {hits.position[i], hits.normal[i]});
        }
      }
      // Each variant's request, warmed up; those the server refuses are dropped.
      struct Trial {
        const Variant* var;
        v1::RenderRequest req;
        TimedRuns runs;
        RenderResult last;
        bool failed = false;  // a timed run failed after the warm-up passed
      };
      // A variant's request under a light; nothing when its JSON does not parse.
      const auto request_for = [&](const Variant& var,
                                   const Light& light) -> std::optional<v1::RenderRequest> {
        v1::RenderRequest req;
        *req.mutable_scene() = scene_proto;
        *req.mutable_camera() = convert::to_proto(cam);
        *req.add_lights() = convert::to_proto(light);
        req.add_products(v1::PRODUCT_VISIBILITY);
        req.add_products(v1::PRODUCT_TEXEL_DENSITY);
        v1::RenderRequest fragment;
        const auto st = google::protobuf::util::JsonStringToMessage(var.json, &fragment);
        if (!st.ok()) {
          std::fprintf(stderr, "variant %s: %s\n", var.name.c_str(), st.ToString().c_str());
          return std::nullopt;
        }
        req.MergeFrom(fragment);
        if (var.ground_class) req.mutable_scene()->mutable_instances(0)->set_receiver_class(0);
        return req;
      };
      std::vector<Trial> trials;
      for (const Variant& var : variants) {
        std::optional<v1::RenderRequest> parsed = request_for(var, view.light);
        if (!parsed) return 2;
        v1::RenderRequest& req = *parsed;
        try {
          client.render(req);  // warm-up
          trials.push_back({&var, std::move(req), {}, {}});
        } catch (const std::exception& e) {
          // Refusals (a technique the light has not) are expected; shown on a terminal only.
          if (terminal)
            std::fprintf(stderr, "\r%s/%s/%s: %s\n", sc.name.c_str(), view.name.c_str(),
                         var.name.c_str(), e.what());
          ++done;
          done_runs += runs;
        }
      }
      // The timed runs, round by round over the view's variants: a burst of load on this shared
      // machine then lands on one run of several variants, which their medians discard, not on
      // every run of one.
      for (int r = 0; r < runs; ++r)
        for (Trial& t : trials) {
          ++done_runs;
          if (t.failed) continue;
          try {
            const auto t0 = std::chrono::steady_clock::now();
            t.last = client.render(t.req);
            t.runs.add(ms_since(t0), t.last.timings);
          } catch (const std::exception& e) {  // unexpected: said on every output
            t.failed = true;
            std::fprintf(stderr, "\r%s/%s/%s failed in a timed run: %s\n", sc.name.c_str(),
                         view.name.c_str(), t.var->name.c_str(), e.what());
          }
          progress();
        }
      for (Trial& trial : trials) {
        if (trial.failed) {
          ++done;
          continue;
        }
        const Variant& var = *trial.var;
        const v1::RenderRequest& req = trial.req;
        const RenderResult& last = trial.last;
        Case c;
        c.scene = sc.name;
        c.view = view.name;
        c.variant = var.name;
        c.soft = var.soft;
        trial.runs.summarize(c);
        if (own && !no_in_process) {
          const RenderRequest engine_req = convert::from_proto(req);
          std::vector<double> t;
          for (int r = 0; r < runs; ++r) {
            const auto t0 = std::chrono::steady_clock::now();
            own->engine().render(engine_req);
            t.push_back(ms_since(t0));
          }
          c.engine_median = median(t);
        }
        std::vector<float>& ref = var.soft ? soft : hard;
        double& ref_boundary = var.soft ? soft_boundary : hard_boundary;
        if (ref.empty()) {
          ref = var.soft ? oracle::camera_area_visibility(oracle, cam, view.light).visibility
                         : oracle.camera_visibility(cam, view.light);
          ref_boundary = oracle::boundary_share(ref, cam.width, cam.height, surface);
        }
        c.error = oracle::compare_visibility(find(last, Product::kVisibility)->data, ref);
        c.bands = oracle::compare_visibility_by_distance(
            find(last, Product::kVisibility)->data, ref, distance, oracle::kStandardDistanceEdges);
        c.density = oracle::density_stats(find(last, Product::kTexelDensity)->data);
        c.boundary = oracle::boundary_share(find(last, Product::kVisibility)->data, cam.width,
                                            cam.height, surface);
        c.reference_boundary = ref_boundary;
        // Default biases only: the bilinear filter tests a receiver plane, so under a changed
        // bias the difference would count acne and peter-panning too.
        const v1::ShadowMapSettings& map = req.shadow_map();
        const bool hard_test =
            !var.soft && !req.has_quality() && (!req.has_filter() || req.filter().has_hard()) &&
            map.technique() != v1::TECHNIQUE_AUTO && !map.has_bias_constant() &&
            !map.has_bias_slope() && !map.has_bias_world_constant() && !map.has_bias_world_texel();
        if (hard_test) {  // one more render, untimed: the same maps filtered bilinear 2x2
          v1::RenderRequest bilinear = req;
          bilinear.mutable_filter()->mutable_pcf2x2();
          try {
            c.edge_estimate = oracle::edge_sampling_estimate(
                find(last, Product::kVisibility)->data,
                find(client.render(bilinear), Product::kVisibility)->data);
          } catch (const std::exception& e) {  // unexpected: the case keeps no estimate
            std::fprintf(stderr, "\r%s/%s/%s filtered 2x2 failed: %s\n", sc.name.c_str(),
                         view.name.c_str(), var.name.c_str(), e.what());
          }
        }
        if (var.name == probe_variant())
          probe_boundary =
              oracle::local_boundary_share(find(last, Product::kVisibility)->data, cam.width,
                                           cam.height, kSampleColumns, kSampleRows, surface);
        if (!calibration_out.empty() && !probe_boundary.empty()) {
          // The technique that ran: AUTO's pick, else the request's (a point light's default
          // is its cube).
          const std::optional<Technique> asked =
              names::kTechniques.from_proto(req.shadow_map().technique());
          const Technique ran = last.light_fits[0].auto_technique
                                    ? *last.light_fits[0].auto_technique
                                : asked                                ? *asked
                                : view.light.type == LightType::kPoint ? Technique::kCube
                                                                       : Technique::kUniform;
          calibration.add_error(ran, find(last, Product::kTexelDensity)->data,
                                find(last, Product::kVisibility)->data, ref, lit_side,
                                probe_boundary);
          RenderRequest as_ran = convert::from_proto(req);  // priced as what ran, not AUTO
          as_ran.shadow_map.technique = ran;
          if (const uint32_t drawn = last.light_fits[0].auto_map_size)
            as_ran.shadow_map.size = drawn;
          MapLoads loads;
          for (const LightFitReport& fit : last.light_fits)
            loads.push_back({fit.raster_overlaps, fit.raster_box_pixels});
          calibration.add_time(as_ran, loads, c.passes, c.device_ms);
          if (asked && *asked != Technique::kAuto)  // a configuration a goal may pick
            calibration.add_measured(sc.name + "/" + view.name, *asked, as_ran.shadow_map.size,
                                     c.error.misclassified_rate());
        }
        c.quality = last.quality;
        c.reused = last.reused;
        if (req.has_quality())
          c.goal = req.quality().has_max_error()
                       ? Quality{Quality::Goal::kMaxError, req.quality().max_error()}
                       : Quality{Quality::Goal::kMaxDeviceMs, req.quality().max_device_ms()};
        set_map_report(c, last.light_fits[0],
                       last.quality                  ? last.quality->size
                       : req.shadow_map().has_size() ? req.shadow_map().size()
                                                     : ShadowMapSettings{}.size);
        if (terminal) {
          std::fprintf(stderr, "\r%-8s %-20s %-28s %8.1f ms  mae %.4f  misclass. by distance",
                       sc.name.c_str(), view.name.c_str(), var.name.c_str(), c.wall_median,
                       c.error.mae);
          for (const oracle::DistanceBand& b : c.bands)
            std::fprintf(stderr, " %s %.3f%%", b.label().c_str(),
                         100 * b.error.misclassified_rate());
          std::fprintf(stderr, "\n");
        }
        ++done;
        progress();
        cases.push_back(std::move(c));
      }
      // Under the nudged lights (frames.hpp), again: the variants compared with AUTO, and the
      // error goals with the fixed configurations they are judged against. Not for the
      // calibration, which counts the views as they are.
      if (!calibration_out.empty()) continue;
      std::vector<std::string> compared;
      for (const Trial& t : trials)
        if (!t.failed && (compared_with_auto(t.var->name) || is_fixed_configuration(t.var->name) ||
                          t.var->json.find("maxError") != std::string::npos))
          compared.push_back(t.var->name);
      const auto render = [&](const std::string& name,
                              const Light& light) -> std::optional<std::vector<float>> {
        const auto t = std::find_if(trials.begin(), trials.end(),
                                    [&](const Trial& t) { return t.var->name == name; });
        try {
          const RenderResult r = client.render(*request_for(*t->var, light));
          return find(r, Product::kVisibility)->data;
        } catch (const std::exception& e) {  // unexpected where the view ran: said everywhere
          std::fprintf(stderr, "\r%s/%s/%s, nudged: %s\n", sc.name.c_str(), view.name.c_str(),
                       name.c_str(), e.what());
          return std::nullopt;
        }
      };
      for (FrameError& f : run_nudged_frames(
               sc.name, view.name, view.light, compared, render,
               [&](const Light& l) { return oracle.camera_visibility(cam, l); }, distance))
        frames.push_back(std::move(f));
    }
  }

  // Per variant: mean time and error, for the plot and its Pareto front. A variant is ranked when
  // it runs on every view of the sweep but those the server refuses, on at least half of them
  // (UNIFORM is refused for point lights, CUBE for other lights): the ranked variants' means are
  // over the views they all ran on, so they compare like for like. Others (run on few views)
  // are listed with their own means but neither plotted nor ranked.
  std::set<std::string> all_views;
  std::map<std::string, std::set<std::string>> views_of;
  for (const Case& c : cases) {
    all_views.insert(c.scene + "/" + c.view);
    views_of[c.variant].insert(c.scene + "/" + c.view);
  }
  auto rankable = [&](const Variant& var) {
    return 2 * views_of[var.name].size() >= all_views.size();
  };
  std::set<std::string> common = all_views;
  for (const Variant& var : variants) {
    if (!rankable(var)) continue;
    std::set<std::string> both;
    for (const std::string& v : views_of[var.name])
      if (common.count(v)) both.insert(v);
    common = std::move(both);
  }
  std::vector<double> vt, ve;
  std::vector<std::string> vn;
  std::vector<int> vcases;
  std::vector<std::string> vpartial;  // why a listed variant is not ranked; empty = ranked
  for (const Variant& var : variants) {
    const bool ranked = rankable(var);
    double t = 0, e = 0;
    int n = 0;
    for (const Case& c : cases) {
      if (c.variant != var.name || (ranked && !common.count(c.scene + "/" + c.view))) continue;
      t += c.wall_median;
      e += c.error.mae;
      ++n;
    }
    if (n == 0) continue;
    vn.push_back(var.name);
    vt.push_back(t / n);
    ve.push_back(e / n);
    vcases.push_back(n);
    vpartial.push_back(ranked ? ""
                              : std::to_string(views_of[var.name].size()) + " of " +
                                    std::to_string(all_views.size()) + " views");
  }
  std::vector<double> pt, pe;  // the variants on every view
  for (size_t i = 0; i < vn.size(); ++i) {
    if (!vpartial[i].empty()) continue;
    pt.push_back(vt[i]);
    pe.push_back(ve[i]);
  }
  const std::vector<bool> every_view_front = pareto_front(pt, pe);
  std::vector<bool> front(vn.size(), false);
  for (size_t i = 0, k = 0; i < vn.size(); ++i)
    if (vpartial[i].empty()) front[i] = every_view_front[k++];

  std::filesystem::create_directories(out_dir);
  const auto dir = std::filesystem::path(out_dir);
  // The variants' summary for the plot (scripts/plot_bench.py): ranked = averaged over the
  // common views (plotted), pareto = on the front among those.
  std::ofstream variants_csv(dir / "variants.csv");
  variants_csv << "variant,cases,mean_wall_ms,mean_mae,ranked,pareto\n";
  for (size_t i = 0; i < vn.size(); ++i)
    variants_csv << vn[i] << ',' << vcases[i] << ',' << vt[i] << ',' << ve[i] << ','
                 << (vpartial[i].empty() ? 1 : 0) << ',' << (front[i] ? 1 : 0) << '\n';

  if (!calibration_out.empty()) {
    // The second pass: each goal candidate's prediction from the bins just counted, which the
    // error margins compare with the measurements above.
    for (const auto& [view, candidates] : goal_candidates(calibration.table(), all_scenes, width))
      calibration.add_predicted(view, candidates);
    std::ofstream out(calibration_out);
    out << calibration.table().to_csv(
        "Misclassified hard-test pixels per probe boundary pixel (a shadow edge on one lit\n"
        "surface; the probe's share in each pixel's sample-grid cell), by texel footprint\n"
        "(pixels whose "
        "seen side faces the light), then each goal candidate's error margin (measured over\n"
        "predicted at its " +
        std::to_string(int(std::lround(100 * kErrorQuantile))) +
        "th percentile over the views), then typical device-time rates (ns\n"
        "per unit) and their margin, written by shadow-bench --calibration\n"
        "over the standard views at " +
        std::to_string(width) + " px wide: " + std::to_string(cases.size()) +
        " cases (uniform, psm, psm_cube, lispsm and auto maps, default biases; the point lights'\n"
        "views have no probe and do not count).");
    std::fprintf(stderr, "wrote %s\n", calibration_out.c_str());
  }

  std::ofstream csv(dir / "results.csv");
  csv << "scene,view,variant,reference,wall_median_ms,wall_min_ms,wall_max_ms,engine_median_ms,"
         "device_ms,mae,rmse,misclassified_rate,penumbra_mae,texel_median_px,texel_p95_px,"
         "texel_above_1,map_faces,map_texels,cube_texel_min,cube_texel_max,boundary,"
         "reference_boundary,passes";
  // Misclassified rate, MAE and pixels per distance band (the bands are the same for every case).
  if (!cases.empty())
    for (const oracle::DistanceBand& b : cases.front().bands)
      csv << ",misclassified " << b.label() << ",mae " << b.label() << ",px " << b.label();
  // A quality goal's candidates as its reply gave them:
  // "uniform 512=<error>/<p90 ms>/<typical ms>;...".
  csv << ",quality_candidates,edge_estimate\n";
  for (const Case& c : cases) {
    csv << c.scene << ',' << c.view << ',' << c.variant << ',' << (c.soft ? "area" : "hard") << ','
        << c.wall_median << ',' << c.wall_min << ',' << c.wall_max << ',' << c.engine_median << ','
        << c.device_ms << ',' << c.error.mae << ',' << c.error.rmse << ','
        << c.error.misclassified_rate() << ',' << c.error.penumbra_mae << ',' << c.density.median
        << ',' << c.density.p95 << ',' << c.density.fraction_above_1 << ',' << c.map_faces << ','
        << c.map_texels << ',' << c.cube_texel_min << ',' << c.cube_texel_max << ',' << c.boundary
        << ',' << c.reference_boundary << ',';
    bool first = true;
    for (const auto& [k, ms] : c.passes) {
      csv << (first ? "" : ";") << k << '=' << ms;
      first = false;
    }
    for (const oracle::DistanceBand& b : c.bands)
      csv << ',' << b.error.misclassified_rate() << ',' << b.error.mae << ',' << b.error.both_valid;
    csv << ',';
    if (c.quality)
      for (const QualityCandidate& q : c.quality->candidates)
        csv << (&q == &c.quality->candidates.front() ? "" : ";")
            << configuration_name(q.technique, q.size) << '=' << q.predicted_error << '/'
            << q.predicted_device_ms << '/' << q.typical_device_ms;
    csv << ',';
    if (c.edge_estimate) csv << *c.edge_estimate;
    csv << '\n';
  }
  std::ofstream frames_csv(dir / "frames.csv");
  frames_csv << "scene,view,variant,frame,light_direction,light_position,misclassified_rate";
  if (!frames.empty())
    for (const oracle::DistanceBand& b : frames.front().bands)
      frames_csv << ",misclassified " << b.label();
  frames_csv << '\n';
  for (const FrameError& f : frames) {
    const glm::vec3 d = f.light.direction, p = f.light.position;
    frames_csv << f.scene << ',' << f.view << ',' << f.variant << ',' << f.frame << ',' << d.x
               << ' ' << d.y << ' ' << d.z << ',' << p.x << ' ' << p.y << ' ' << p.z << ','
               << f.error.misclassified_rate();
    for (const oracle::DistanceBand& b : f.bands) frames_csv << ',' << b.error.misclassified_rate();
    frames_csv << '\n';
  }

  std::ofstream md(dir / "results.md");
  char line[512];
  md << "# shadow-bench results\n\n";
  md << "Device: " << (own ? own->engine().device_name() : std::string("(remote server)")) << "; "
     << std::thread::hardware_concurrency() << " hardware threads; camera " << width << "x"
     << width * 9 / 16 << "; " << runs << " timed runs after one warm-up"
     << (full ? " (--full)" : "") << ".\n\n";
  md << "## Variants (plotted in pareto.png)\n\n"
        "pareto.png (scripts/plot_bench.py): x = mean gRPC wall time per request (ms, log "
        "scale), y = mean visibility MAE against the Embree oracle; each variant labelled, the "
        "Pareto front joined by a line. near_error.png: the misclassified rate within 10 m of "
        "the eye per view for the equal-texel variants below. Ranked variants are averaged over "
        "the "
     << common.size() << " of " << all_views.size()
     << " views they all ran on (the server refuses some variants on some views: UNIFORM for "
        "point lights, CUBE for other lights, PCSS and blur for cubes); a variant run on few "
        "views is listed with the mean over its own cases, neither plotted nor ranked.\n\n"
        "| variant | cases | mean wall ms | mean MAE | Pareto |\n|---|---:|---:|---:|:---:|\n";
  for (size_t i = 0; i < vn.size(); ++i) {
    const std::string pareto = !vpartial[i].empty() ? vpartial[i] : (front[i] ? "yes" : "");
    std::snprintf(line, sizeof line, "| %s | %d | %.1f | %.5f | %s |\n", vn[i].c_str(), vcases[i],
                  vt[i], ve[i], pareto.c_str());
    md << line;
  }
  write_equal_texel_section(cases, md);
  write_auto_section(cases, frames, md);
  write_quality_section(cases, frames, md);
  {
    std::ofstream ceiling_csv(dir / "goal_ceiling.csv");
    write_goal_ceiling(cases, frames, md, ceiling_csv);
  }
  write_edge_estimate_section(cases, md);
  md << "\n## Cases\n\nwall = gRPC round trip (median [min, max]); engine = the same request "
        "in-process; device = sum of the server's pass timings. Errors vs the Embree oracle "
        "(hard shadow rays, or area-light visibility for soft variants): MAE, misclassified "
        "(|v - v_ref| > 0.5) and penumbra MAE. Texel = size of a shadow-map texel in pixels "
        "(median, p95, share > 1). Map texels = the maps drawn (cube faces, else 1) x size^2.\n\n"
        "| scene | view | variant | wall ms | engine ms | device ms | MAE | misclass. | "
        "penumbra MAE | texel med | texel p95 | texel > 1 | map texels (M) |\n"
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Case& c : cases) {
    std::snprintf(line, sizeof line,
                  "| %s | %s | %s | %.1f [%.1f, %.1f] | %.1f | %.1f | %.5f | %.3f%% | %.4f | "
                  "%.3g | %.3g | %.1f%% | %.2f |\n",
                  c.scene.c_str(), c.view.c_str(), c.variant.c_str(), c.wall_median, c.wall_min,
                  c.wall_max, c.engine_median, c.device_ms, c.error.mae,
                  100 * c.error.misclassified_rate(), c.error.penumbra_mae, c.density.median,
                  c.density.p95, 100 * c.density.fraction_above_1, double(c.map_texels) / 1e6);
    md << line;
  }
  if (!cases.empty()) {
    md << "\n## Error by distance from the eye\n\nMisclassified rate and MAE (hard or area "
          "reference as above) over the pixels whose surface lies in each band of distance from "
          "the eye; px = pixels in the band. PSM's claim is about the near band.\n\n"
          "| scene | view | variant |";
    for (const oracle::DistanceBand& b : cases.front().bands)
      md << ' ' << b.label() << " misclass. | MAE | px |";
    md << "\n|---|---|---|";
    for (size_t i = 0; i < cases.front().bands.size(); ++i) md << "---:|---:|---:|";
    md << '\n';
    for (const Case& c : cases) {
      md << "| " << c.scene << " | " << c.view << " | " << c.variant << " |";
      for (const oracle::DistanceBand& b : c.bands) {
        std::snprintf(line, sizeof line, " %.3f%% | %.5f | %zu |",
                      100 * b.error.misclassified_rate(), b.error.mae, b.error.both_valid);
        md << line;
      }
      md << '\n';
    }
  }
  if (terminal) std::fprintf(stderr, "\n");
  std::fprintf(stderr,
               "wrote %s/results.md, results.csv, variants.csv, frames.csv, goal_ceiling.csv (%zu "
               "cases, %zu nudged, "
               "%.0f s)\n",
               out_dir.c_str(), cases.size(), frames.size(), ms_since(started) / 1e3);
  return 0;
}
