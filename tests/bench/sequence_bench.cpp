// shadow-sequence-bench (issue 15): a shot rendered as a sequence against the same frames sent as
// independent inline requests, in one run, through the real server on loopback. The scene is the
// raster bench's 10^6-triangle sphere crowd plus one small sphere that may move. Cases:
//   static sun, moving camera  (the sun's map is fitted to the scene, so it can be kept)
//   moving sphere, static camera
// For each: frames/s (also of the frames sent as independent requests naming the uploaded scene,
// where no instance moves), bytes on the wire (requests and replies, serialized sizes), and the
// share of device time the kept passes saved (their time in the first frame, per later frame).
// Then TECHNIQUE_AUTO on the standard street, walking 10 cm a frame or under a sun turning 0.5
// degrees a frame: the sequence and the same frames as requests by scene id, which both keep
// each trial while its prediction holds, against the frames as inline requests, each with its
// own trial: device time per frame, trials run, and the picks (where they differ, and how often
// each switches technique between consecutive frames).
//
//   shadow-sequence-bench [--frames 100] [--independent 20] [--size 1280x720] [--map 2048]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/plan/sequence.hpp"
#include "machine_context.hpp"
#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/standard_scenes.hpp"
#include "raster_scenes.hpp"
#include "scenes/shapes.hpp"
#include "service/server.hpp"
#include "shadow_client.hpp"
#include "wire/convert.hpp"

namespace {

using namespace shadow;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Totals {
  double wall_ms = 0;
  uint64_t request_bytes = 0, reply_bytes = 0;
  size_t frames = 0;
  double device_ms = 0;
};

uint64_t reply_bytes(const RenderResult& r) {
  uint64_t bytes = 0;
  for (const Texture& t : r.textures) bytes += t.byte_size();
  return bytes;
}

double device_ms(const RenderResult& r) {
  double ms = 0;
  for (const PassTiming& t : r.timings) ms += t.device_ms;
  return ms;
}

// The crowd (instance 0) and a sphere (instance 1) at x = 0, z = 0, 3 m up.
SequenceRequest shot(uint32_t width, uint32_t height, uint32_t map) {
  SequenceRequest s;
  auto scene = std::make_shared<Scene>(bench::one_instance(bench::sphere_crowd().mesh));
  scene->meshes.push_back(scenes::make_sphere(32, 16));
  Instance sphere{1};
  sphere.transform = glm::translate(glm::mat4(1.0f), glm::vec3(0, 3, 0));
  scene->instances.push_back(sphere);
  RenderRequest& r = s.base;
  r.scene = scene;
  r.camera.eye = {40, 25, 60};
  r.camera.target = {0, 0, 0};
  r.camera.width = width, r.camera.height = height;
  r.camera.near = 0.5f, r.camera.far = 400;
  r.lights[0].direction = glm::normalize(glm::vec3(0.6f, -1.0f, -0.3f));
  r.shadow_map.size = map;
  r.shadow_map.fit = MapFit::kScene;
  r.products = {Product::kVisibility};
  return s;
}

void move_camera(SequenceRequest& s, size_t frames) {
  s.frames.assign(frames, {});
  for (size_t i = 0; i < frames; ++i) {
    Camera c = s.base.camera;
    const float a = 0.01f * float(i);
    c.eye = glm::vec3(40 * std::cos(a) + 20 * std::sin(a), 25, 60 * std::cos(a) - 30 * std::sin(a));
    s.frames[i].camera = c;
  }
}

void move_sphere(SequenceRequest& s, size_t frames) {
  s.frames.assign(frames, {});
  for (size_t i = 0; i < frames; ++i)
    s.frames[i].transforms = {
        {1, glm::translate(glm::mat4(1.0f), glm::vec3(0.2f * float(i) - 10, 3, 0))}};
}

// The frames as independent Render requests: inline, or naming `scene_id` (only frames that
// move no instance: a request by id cannot), when each continues the last one's results.
Totals independent(client::ShadowClient& c, const SequenceRequest& s, size_t count,
                   const std::string& scene_id = "") {
  Totals t;
  const auto t0 = Clock::now();
  for (size_t i = 0; i < count; ++i) {
    v1::RenderRequest request = convert::to_proto(frame_request(s, i));
    if (!scene_id.empty()) request.set_scene_id(scene_id);  // replaces the inline scene
    t.request_bytes += request.ByteSizeLong();
    const RenderResult r = c.render(request, std::chrono::minutes(10));
    t.reply_bytes += reply_bytes(r);
    t.device_ms += device_ms(r);
    ++t.frames;
  }
  t.wall_ms = ms_since(t0);
  return t;
}

struct SequenceTotals : Totals {
  double upload_ms = 0;
  double first_device_ms = 0;
  std::map<std::string, double> first_pass_ms;  // frame 0's passes
  double kept_ms = 0;                           // sum over frames of frame 0's time of kept passes
};

SequenceTotals sequence(client::ShadowClient& c, const SequenceRequest& s) {
  SequenceTotals t;
  v1::SequenceRequest request = convert::to_proto(s);
  const auto t0 = Clock::now();
  const std::string id = c.upload_scene(request.base().scene(), std::chrono::minutes(10));
  t.request_bytes += request.base().scene().ByteSizeLong();
  t.upload_ms = ms_since(t0);
  request.mutable_base()->set_scene_id(id);
  t.request_bytes += request.ByteSizeLong();
  c.render_sequence(
      request,
      [&](RenderResult&& r) {
        t.reply_bytes += reply_bytes(r);
        t.device_ms += device_ms(r);
        if (r.frame == 0) {
          t.first_device_ms = device_ms(r);
          for (const PassTiming& p : r.timings) t.first_pass_ms[p.pass] += p.device_ms;
        }
        for (const std::string& kept : r.reused)
          for (const auto& [pass, ms] : t.first_pass_ms)
            if (pass == kept || pass.rfind(kept + ".", 0) == 0) t.kept_ms += ms;
        ++t.frames;
      },
      std::chrono::minutes(30));
  t.wall_ms = ms_since(t0);
  return t;
}

void report(const char* name, const Totals& ind, const Totals* by_id, const SequenceTotals& seq) {
  const double ind_fps = 1000.0 * ind.frames / ind.wall_ms;
  const double seq_fps = 1000.0 * seq.frames / seq.wall_ms;
  char by_id_fps[32] = "-";
  if (by_id)
    std::snprintf(by_id_fps, sizeof by_id_fps, "%.2f", 1000.0 * by_id->frames / by_id->wall_ms);
  std::printf("| %s | %.2f | %s | %.2f (upload %.0f ms) | **%.1fx** | %.1f | %.1f | %.0f%% |\n",
              name, ind_fps, by_id_fps, seq_fps, seq.upload_ms, seq_fps / ind_fps,
              (ind.request_bytes + ind.reply_bytes) / double(ind.frames) / 1048576.0,
              (seq.request_bytes + seq.reply_bytes) / double(seq.frames) / 1048576.0,
              100.0 * seq.kept_ms / (seq.device_ms + seq.kept_ms));
}

// AUTO at 2048^2 on the street's overview: the camera walking 10 cm a frame along its view, or
// the sun turning 0.5 degrees a frame about the vertical.
// The street's overview (eye height, a side sun) at width x height, visibility only.
RenderRequest street_overview(uint32_t width, uint32_t height) {
  const scenes::StandardScene street = scenes::street();
  RenderRequest r;
  r.scene = street.scene;
  r.camera = street.views[0].camera;
  r.camera.width = width, r.camera.height = height;
  r.lights.assign(1, street.views[0].light);
  r.products = {Product::kVisibility};
  return r;
}

SequenceRequest street_shot(size_t frames, uint32_t width, uint32_t height, bool walk) {
  SequenceRequest s;
  s.base = street_overview(width, height);
  RenderRequest& r = s.base;
  r.shadow_map.technique = Technique::kAuto;
  r.shadow_map.size = 2048;
  glm::vec3 ahead = r.camera.target - r.camera.eye;
  ahead.y = 0;
  ahead = 0.1f * glm::normalize(ahead);
  s.frames.assign(frames, {});
  for (size_t i = 0; i < frames; ++i) {
    if (walk) {
      Camera c = r.camera;
      c.eye += float(i) * ahead, c.target += float(i) * ahead;
      s.frames[i].camera = c;
    } else {
      Light l = r.lights[0];
      l.direction = glm::vec3(
          glm::rotate(glm::mat4(1.0f), glm::radians(0.5f * float(i)), glm::vec3(0, 1, 0)) *
          glm::vec4(l.direction, 0.0f));
      s.frames[i].lights = std::vector<Light>(1, l);
    }
  }
  return s;
}

// Per frame: AUTO's pick, its visibility, whether its trial ran, its device time (without the
// scene's upload, which an inline request pays each time).
struct AutoFrames {
  std::vector<Technique> picks;
  std::vector<std::vector<float>> visibility;
  size_t trials = 0, switches = 0;
  double device_ms = 0;
  void add(const RenderResult& r) {
    const Technique t = r.light_fits.at(0).auto_technique.value();
    switches += !picks.empty() && picks.back() != t;
    picks.push_back(t);
    visibility.push_back(r.textures.at(0).data);
    trials += std::any_of(r.timings.begin(), r.timings.end(), [](const PassTiming& p) {
      return p.pass.find("light_fit.trial.") != std::string::npos;
    });
    for (const PassTiming& p : r.timings)
      if (!p.pass.starts_with("scene.")) device_ms += p.device_ms;
  }
  // Its table cells; `base`: a shot whose device time this one's is given as a ratio to.
  std::string columns(const AutoFrames* base = nullptr) const {
    char ratio[32] = "";
    if (base) std::snprintf(ratio, sizeof ratio, " (**%.2fx**)", device_ms / base->device_ms);
    char out[128];
    std::snprintf(out, sizeof out, "%.1f%s | %zu | %zu", device_ms / double(picks.size()), ratio,
                  trials, switches);
    return out;
  }
};

// One row per shot: its frames as separate inline requests (each with its own trial), as
// requests by scene id (each continuing the last, so keeping a trial as a sequence does), and
// as a sequence.
void auto_shot(client::ShadowClient& c, const char* name, const SequenceRequest& s) {
  v1::SequenceRequest request = convert::to_proto(s);
  const std::string id = c.upload_scene(request.base().scene(), std::chrono::minutes(10));
  request.mutable_base()->set_scene_id(id);
  AutoFrames seq, by_id, own;
  c.render_sequence(
      request, [&](RenderResult&& r) { seq.add(r); }, std::chrono::minutes(30));
  for (size_t i = 0; i < s.frames.size(); ++i) {
    v1::RenderRequest one = convert::to_proto(frame_request(s, i));
    own.add(c.render(one, std::chrono::minutes(10)));
    one.set_scene_id(id);
    by_id.add(c.render(one, std::chrono::minutes(10)));
  }
  // Where the sequence's picks differ from the frames' own trials, both against shadow rays.
  const oracle::RayOracle rays(*s.base.scene);
  size_t differ = 0;
  double seq_wrong = 0, own_wrong = 0;
  for (size_t i = 0; i < s.frames.size(); ++i) {
    if (seq.picks[i] == own.picks[i]) continue;
    const RenderRequest frame = frame_request(s, i);
    const std::vector<float> ref = rays.camera_visibility(frame.camera, frame.lights[0]);
    seq_wrong += oracle::compare_visibility(seq.visibility[i], ref).misclassified_rate();
    own_wrong += oracle::compare_visibility(own.visibility[i], ref).misclassified_rate();
    ++differ;
  }
  char wrong[64] = "-";
  if (differ)
    std::snprintf(wrong, sizeof wrong, "%.3f%% / %.3f%%", 100 * seq_wrong / double(differ),
                  100 * own_wrong / double(differ));
  std::printf("| %s | %s | %s | %s | %zu | %s |\n", name, own.columns().c_str(),
              by_id.columns(&own).c_str(), seq.columns(&own).c_str(), differ, wrong);
}

// Virtual shadow maps on a dolly along the street at eye height (issue 53): `frames` frames 2 m
// apart, a still sun, a static scene, as one sequence. Per frame, the pages resident and drawn,
// and the misclassified pixels against shadow rays; then the goals' summary.
void virtual_dolly(client::ShadowClient& c, size_t frames, uint32_t width, uint32_t height) {
  SequenceRequest s;
  s.base = street_overview(width, height);
  RenderRequest& r = s.base;
  r.filter.kind = FilterKind::kHard;
  r.shadow_map.technique = Technique::kVirtual;
  r.shadow_map.size = 16384;
  for (size_t i = 0; i < frames; ++i) {
    Frame f;
    Camera cam = r.camera;
    cam.eye.z -= 2.0f * float(i), cam.target.z -= 2.0f * float(i);
    f.camera = cam;
    s.frames.push_back(f);
  }
  const oracle::RayOracle rays(*r.scene);
  // The same frames with a dense uniform 4096^2 map: how much of a frame's error is the view's.
  SequenceRequest dense = s;
  dense.base.shadow_map.technique = Technique::kUniform;
  dense.base.shadow_map.size = 4096;
  std::vector<double> dense_wrong;
  c.render_sequence(
      convert::to_proto(dense),
      [&](RenderResult&& f) {
        const std::vector<float> ref =
            rays.camera_visibility(*s.frames[f.frame].camera, r.lights[0]);
        dense_wrong.push_back(
            100 * oracle::compare_visibility(f.textures.at(0).data, ref).misclassified_rate());
      },
      std::chrono::minutes(30));
  std::vector<double> wrong, drawn_share;
  double kept_ms = 0;
  std::printf(
      "\n| frame | pages resident | drawn | drawn share | misclassified | uniform 4096^2 "
      "misclassified | device ms |\n| --- | --- | --- | --- | --- | --- | --- |\n");
  c.render_sequence(
      convert::to_proto(s),
      [&](RenderResult&& f) {
        const size_t i = f.frame;
        const VirtualPageCounts& p = f.virtual_pages.value();
        const std::vector<float> ref = rays.camera_visibility(*s.frames[i].camera, r.lights[0]);
        wrong.push_back(
            100 * oracle::compare_visibility(f.textures.at(0).data, ref).misclassified_rate());
        const double share = double(p.rendered) / double(p.resident);
        if (i > 0) drawn_share.push_back(share), kept_ms += device_ms(f);
        std::printf("| %zu | %llu | %llu | %.1f%% | %.3f%% | %.3f%% | %.1f |\n", i,
                    (unsigned long long)p.resident, (unsigned long long)p.rendered, 100 * share,
                    wrong.back(), dense_wrong.at(i), device_ms(f));
      },
      std::chrono::minutes(30));
  if (drawn_share.empty()) return;  // one frame: nothing kept to sum up
  std::vector<double> sorted = wrong, dense_sorted = dense_wrong;
  std::sort(sorted.begin(), sorted.end());
  std::sort(dense_sorted.begin(), dense_sorted.end());
  const double median = sorted[sorted.size() / 2];
  double mean_share = 0;
  for (double d : drawn_share) mean_share += d / double(drawn_share.size());
  std::printf(
      "\nAfter the first frame: drawn share mean %.1f%%, max %.1f%%; misclassified median "
      "%.3f%%, worst frame %.3f%% (%.2fx the median); device ms per frame %.1f. Uniform "
      "4096^2: median %.3f%%, worst frame %.2fx the median\n",
      100 * mean_share, 100 * *std::max_element(drawn_share.begin(), drawn_share.end()), median,
      sorted.back(), sorted.back() / median, kept_ms / double(drawn_share.size()),
      dense_sorted[dense_sorted.size() / 2],
      dense_sorted.back() / dense_sorted[dense_sorted.size() / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"shadow-sequence-bench: a sequence against independent inline requests"};
  size_t frames = 100, independent_frames = 20;
  uint32_t width = 1280, height = 720, map = 2048;
  app.add_option("--frames", frames, "frames in each sequence")->capture_default_str();
  app.add_option("--independent", independent_frames,
                 "frames sent as independent inline requests (their rate is per frame)")
      ->capture_default_str();
  app.add_option("--map", map, "shadow-map size")->capture_default_str();
  size_t auto_frames = 96;
  app.add_option("--auto-frames", auto_frames, "frames of each AUTO shot (0: none)")
      ->capture_default_str();
  size_t virtual_frames = 30;
  bool virtual_only = false;
  app.add_option("--virtual-frames", virtual_frames, "frames of the virtual dolly (0: none)")
      ->capture_default_str();
  app.add_flag("--virtual-only", virtual_only, "only the virtual dolly");
  CLI11_PARSE(app, argc, argv);

  service::tune_allocator();  // as shadow-server does
  service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  options.engine.max_request_cost_ms = 0;
  service::ShadowServer server(options);
  client::ShadowClient c(server.address());
  std::printf("machine: %s, %u threads, %s\n", bench::cpu_model().c_str(),
              std::thread::hardware_concurrency(), server.engine().device_name().c_str());
  std::printf(
      "scene: 10^6-triangle sphere crowd + a moving sphere; %ux%u visibility, %u^2 map, "
      "fit scene\n\n",
      width, height, map);
  std::printf(
      "| case | independent frames/s | by scene id frames/s | sequence frames/s | ratio "
      "| MiB/frame independent | MiB/frame sequence | device time kept |\n| --- | --- | "
      "--- | --- | --- | --- | --- | --- |\n");
  if (virtual_only) {
    virtual_dolly(c, virtual_frames, width, height);
    return 0;
  }
  for (int which = 0; which < 2; ++which) {
    SequenceRequest s = shot(width, height, map);
    if (which == 0)
      move_camera(s, frames);
    else
      move_sphere(s, frames);
    const Totals ind = independent(c, s, std::min(independent_frames, frames));
    std::optional<Totals> by_id;
    if (which == 0)
      by_id = independent(
          c, s, std::min(independent_frames, frames),
          c.upload_scene(convert::to_proto(s).base().scene(), std::chrono::minutes(10)));
    const SequenceTotals seq = sequence(c, s);
    report(which == 0 ? "static sun, moving camera" : "moving sphere, static camera", ind,
           by_id ? &*by_id : nullptr, seq);
  }
  if (auto_frames > 0) {
    std::printf(
        "\nTECHNIQUE_AUTO at 2048^2 on the street overview, %zu frames at %ux%u: as inline "
        "requests (each with its own trial), as requests by scene id and as a sequence (both "
        "keeping a trial while its prediction holds). Device ms per frame without the scene's "
        "upload; the ratios are to the inline requests':\n\n| shot | inline: device ms per "
        "frame | trials | technique switches | by scene id: device ms per frame | trials | "
        "switches | sequence: device ms per frame | trials | switches | frames the sequence "
        "picked unlike their own trial | their misclassified share: sequence / own trial |\n"
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
        auto_frames, width / 2, height / 2);
    auto_shot(c, "walking 10 cm a frame", street_shot(auto_frames, width / 2, height / 2, true));
    auto_shot(c, "the sun turning 0.5 deg a frame",
              street_shot(auto_frames, width / 2, height / 2, false));
  }
  if (virtual_frames > 0) virtual_dolly(c, virtual_frames, width, height);
  return 0;
}
