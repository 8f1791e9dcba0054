// shadow-atlas-bench (issue 14): soft shadows through the shadow atlas against PCSS, in the form
// of seed 004's Table 1 (ratios to PCSS), in one run, in-process. The scene: spheres floating
// 0.3-3 m over a 24 m ground, all with their own UVs, under a sun of 3 degrees. For each of
// pcss, atlas_sat and atlas_mip:
//   frame   the device time a camera frame costs once the light's work is done: frames 1.. of a
//           RenderSequence whose camera turns a little each frame under a still sun (the
//           G-buffer and the visibility pass; everything else is kept),
//   bake    the light's work, from the sequence's first frame (the map; for the atlas also its
//           bake, hard test, gutter and SAT or mips, and the blocker search and soft lookup per
//           atlas texel), amortized over 1, 10 and 100 frames,
//   error   against the Embree area-light oracle at 640x360: mean |error|, over the penumbra
//           (0.02 < oracle < 0.98), the share of pixels off by more than 0.1, and the mean
//           within 4 atlas texels of a chart's border (seams) and elsewhere.
// Medians of --repeat frames (and of --repeat sequences' bakes).
//
//   shadow-atlas-bench [--size 1280x720] [--map 2048] [--tile 512] [--repeat 5] [--passes]
//                      [--images DIR]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "atlas_standard.hpp"
#include "engine/engine.hpp"
#include "machine_context.hpp"
#include "oracle/area_light.hpp"
#include "oracle/metrics.hpp"
#include "sphere_field.hpp"

namespace {

using namespace shadow;

struct Split {
  double frame = 0, bake = 0;  // device ms
};

// The camera's passes (per frame) and the light's (the bake), device time.
Split split(const RenderResult& r) {
  Split s;
  for (const PassTiming& t : r.timings) {
    const std::string& n = t.pass;
    if (n.starts_with("gbuffer") || n.starts_with("visibility."))
      s.frame += t.device_ms;
    else if (!n.starts_with("scene") && !n.starts_with("readback"))
      s.bake += t.device_ms;
  }
  return s;
}

// Per camera pixel: whether the surface it sees lies within `texels` atlas texels of its chart's
// border (in this scene every chart is its mesh's whole UV square: the ground's edges, the
// spheres' seam at u = 0, 1 and their poles), from the oracle's hits, in double.
std::vector<uint8_t> near_seams(const Scene& scene, const oracle::CameraHits& hits, double texels,
                                uint32_t tile) {
  std::vector<uint8_t> out(hits.size(), 0);
  const double margin = texels / tile;
  for (size_t p = 0; p < hits.size(); ++p) {
    if (!hits.hit(p)) continue;
    const Instance& inst = scene.instances[hits.instance[p]];
    const Mesh& m = scene.meshes[inst.mesh];
    const glm::dmat4 to_world(inst.transform);
    glm::dvec3 v[3];
    glm::dvec2 uv[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = m.indices[3 * size_t(hits.triangle[p]) + k];
      v[k] = glm::dvec3(to_world * glm::dvec4(m.positions[3 * i], m.positions[3 * i + 1],
                                              m.positions[3 * i + 2], 1.0));
      uv[k] = glm::dvec2(m.uvs[2 * i], m.uvs[2 * i + 1]);
    }
    const glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]), x = hits.position[p] - v[0];
    const double b = glm::dot(glm::cross(x, v[2] - v[0]), n) / glm::dot(n, n);
    const double c = glm::dot(glm::cross(v[1] - v[0], x), n) / glm::dot(n, n);
    const glm::dvec2 t = uv[0] + b * (uv[1] - uv[0]) + c * (uv[2] - uv[0]);
    out[p] = std::min({t.x, t.y, 1 - t.x, 1 - t.y}) < margin;
  }
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("shadow-atlas-bench: atlas soft shadows against PCSS (seed 004, Table 1)");
  std::string size = "1280x720";
  uint32_t map = 2048, tile = 512, repeat = 5, gutter = AtlasSettings{}.gutter;
  bool passes = false, standard = false;
  std::string images;
  std::vector<std::string> scenes;
  app.add_option("--images", images,
                 "write each technique's and the oracle's 640x360 visibility to DIR/NAME.f32 "
                 "(scripts/plot_atlas.py draws them)");
  app.add_flag("--passes", passes, "print each technique's passes and their device time");
  app.add_flag("--standard", standard,
               "instead: the standard scenes' views at 640x360, in layouts the server generates");
  app.add_option("--scenes", scenes, "with --standard: only these scenes (chess, street, ...)")
      ->delimiter(',');
  app.add_option("--size", size, "camera WxH for the timings");
  app.add_option("--map", map, "shadow-map size");
  app.add_option("--tile", tile, "atlas tile size (0: sized from the world, --density)");
  double density = 0;
  app.add_option("--density", density,
                 "with --standard --tile 0: world units per atlas texel (0: the map's footprint)");
  app.add_option("--gutter", gutter, "atlas gutter in texels");
  app.add_option("--repeat", repeat, "renders per technique (medians)");
  CLI11_PARSE(app, argc, argv);
  uint32_t width = 0, height = 0;
  if (std::sscanf(size.c_str(), "%ux%u", &width, &height) != 2) return 2;

  EngineOptions options;
  options.max_request_cost_ms = 0;  // a bench: generated layouts of large meshes take seconds
  Engine engine(options);
  std::printf("machine: %s, %u cores, %s\n", bench::cpu_model().c_str(),
              std::thread::hardware_concurrency(), engine.device_name().c_str());
  if (standard) {
    bench::standard_scenes_table(engine, {map, tile, density, scenes, images});
    return 0;
  }
  const std::pair<const char*, FilterKind> kinds[] = {{"pcss", FilterKind::kPcss},
                                                      {"atlas_sat", FilterKind::kAtlasSat},
                                                      {"atlas_mip", FilterKind::kAtlasMip}};

  // The oracle at 640x360, once.
  RenderRequest small = bench::sphere_field(640, 360, map, tile);
  small.atlas.gutter = gutter;
  const oracle::RayOracle rays(*small.scene);
  const oracle::AreaVisibility truth =
      oracle::camera_area_visibility(rays, small.camera, small.lights[0]);

  std::printf(
      "\n%ux%u camera, %u map, %u-texel tiles (%zu receivers), gutter %u, sun of 3 "
      "degrees\n",
      width, height, map, tile, small.scene->instances.size(), gutter);
  if (!images.empty()) {
    std::filesystem::create_directories(images);
    bench::write_floats(images, "oracle", truth.visibility);
  }
  const std::vector<uint8_t> seams =
      near_seams(*small.scene, rays.cast_camera(small.camera), 4, tile);
  std::printf(
      "| technique | frame ms | vs PCSS | bake ms | 1 frame | 10 frames | 100 frames | "
      "mean err | penumbra err | >0.1 | near seams | elsewhere |\n| --- | --- | --- | --- | "
      "--- | --- | --- | --- | --- | --- | --- | --- |\n");
  double pcss_frame = 0;
  for (const auto& [name, kind] : kinds) {
    RenderRequest req = bench::sphere_field(width, height, map, tile);
    req.atlas.gutter = gutter;
    req.filter.kind = kind;
    // Each sequence: a frame that bakes, then `repeat` frames that only move the camera.
    SequenceRequest sequence{req, std::vector<Frame>(repeat + 1)};
    for (uint32_t i = 0; i <= repeat; ++i) {
      Camera& c = sequence.frames[i].camera.emplace(req.camera);
      c.eye = glm::vec3(
          glm::rotate(glm::mat4(1.0f), glm::radians(0.5f * float(i)), glm::vec3(0, 1, 0)) *
          glm::vec4(c.eye, 1.0f));
    }
    std::vector<double> frames, bakes;
    for (uint32_t k = 0; k < repeat; ++k)
      engine.render_sequence(sequence, [&](RenderResult&& r) {
        const Split s = split(r);
        (r.frame == 0 ? bakes : frames).push_back(r.frame == 0 ? s.bake : s.frame);
        if (passes && k == 0 && r.frame <= 1)
          for (const PassTiming& t : r.timings)
            std::printf("  frame %u: %s %.2f ms\n", r.frame, t.pass.c_str(), t.device_ms);
      });
    const double frame = median(frames), bake = median(bakes);
    if (kind == FilterKind::kPcss) pcss_frame = frame;

    small.filter.kind = kind;
    const RenderResult r = engine.render(small);
    if (!images.empty()) bench::write_floats(images, name, r.textures.at(0).data);
    const oracle::VisibilityError e =
        oracle::compare_visibility(r.textures.at(0).data, truth.visibility);
    size_t far_off = 0;
    for (size_t p = 0; p < truth.visibility.size(); ++p)
      far_off += std::abs(r.textures[0].data[p] - truth.visibility[p]) > 0.1f;
    size_t at_seams = 0, away = 0;
    const double seam_err =
        bench::mean_error(r.textures[0].data, truth.visibility, seams, 1, at_seams);
    const double away_err = bench::mean_error(r.textures[0].data, truth.visibility, seams, 0, away);
    std::printf(
        "| %s | %.1f | %.2fx | %.1f | %.1f | %.1f | %.1f | %.4f | %.4f | %.2f%% | %.4f | "
        "%.4f |\n",
        name, frame, pcss_frame / frame, bake, bake + frame, bake / 10 + frame, bake / 100 + frame,
        e.mae, e.penumbra_mae, 100.0 * double(far_off) / double(std::max<size_t>(e.both_valid, 1)),
        seam_err, away_err);
  }
  size_t seam_pixels = 0;
  for (uint8_t v : seams) seam_pixels += v;
  std::printf(
      "\n(amortized columns: ms per frame with the bake shared by that many frames; "
      "oracle: %zu unconverged of %zu pixels; near seams: the %zu pixels within 4 atlas "
      "texels of a chart's border)\n",
      truth.unconverged, truth.visibility.size(), seam_pixels);
  return 0;
}
