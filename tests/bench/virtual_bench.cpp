// shadow-virtual-bench: virtual shadow maps (issue 53) against the dense maps the service offers,
// on the standard scenes' views at 1280x720 (suns, spot lights and point lights), hard visibility
// against Embree's shadow rays from the engine's own surface points: misclassified pixels, pages
// requested and resident, the pool and device ms. `--bias` sweeps virtual_lod_bias (pages against
// error); `--csv FILE` writes every row for scripts/plot_virtual.py; `--pictures DIR` writes each
// view's virtual levels per pixel for the pictures. `--pcss` measures PCSS instead, at 640x360,
// against the area-light oracle (mean |error| over the seen pixels and the reference's penumbrae).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "engine/engine.hpp"
#include "engine/plan/technique.hpp"
#include "oracle/area_light.hpp"
#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/standard_scenes.hpp"

namespace {

using namespace shadow;

struct Row {
  std::string view, technique;
  uint32_t size = 0;
  double bias = 0, misclassified = 0, device_ms = 0, estimate_ms = 0, estimate_mib = 0;
  double mae = 0, penumbra_mae = 0;  // --pcss
  VirtualPageCounts pages;
};

double device_ms(const RenderResult& r) {
  double ms = 0;
  for (const PassTiming& t : r.timings) ms += t.device_ms;
  return ms;
}

const Texture& texture(const RenderResult& r, Product p) {
  for (const Texture& t : r.textures)
    if (t.kind == p) return t;
  throw std::runtime_error("a product missing from the reply");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"virtual shadow maps against dense maps on the standard views"};
  std::vector<double> biases = {-0.5};  // the default
  std::string csv, only, pictures;
  bool dense = true, passes = false, pcss = false;
  app.add_option("--bias", biases, "virtual_lod_bias values to measure");
  app.add_option("--csv", csv, "write every row here");
  app.add_option("--view", only, "only views whose scene/view name holds this");
  app.add_flag("!--no-dense", dense, "measure virtual maps only");
  app.add_flag("--passes", passes, "print each render's device ms per pass");
  app.add_flag("--pcss", pcss, "PCSS at 640x360 against the area-light oracle");
  app.add_option("--pictures", pictures,
                 "write each view's virtual levels, positions and visibility at the first bias "
                 "here (raw float32, for scripts/plot_virtual.py --pictures)");
  CLI11_PARSE(app, argc, argv);

  EngineOptions options;
  options.max_request_cost_ms = 0;
  Engine engine(options);
  std::vector<Row> rows;
  std::printf("%-28s %-9s %6s %5s %8s %9s %9s %8s %9s %9s %8s\n",
              pcss ? "scene/view (640x360, PCSS)" : "scene/view (1280x720)", "technique", "size",
              "bias", "miscls%", "requested", "resident", "pool MiB", "device ms", "est. ms",
              "est. MiB");
  for (const scenes::StandardScene& sc : scenes::standard_scenes()) {
    std::unique_ptr<oracle::RayOracle> oracle;
    for (const scenes::View& v : sc.views) {
      const std::string name = sc.name + "/" + v.name;
      if (name.find(only) == std::string::npos) continue;
      if (!oracle) oracle = std::make_unique<oracle::RayOracle>(*sc.scene);
      RenderRequest r;
      r.scene = sc.scene;
      r.camera = v.camera;
      r.camera.width = pcss ? 640 : 1280, r.camera.height = pcss ? 360 : 720;
      r.lights = {v.light};
      r.filter.kind = pcss ? FilterKind::kPcss : FilterKind::kHard;
      if (pcss && v.light.type == LightType::kPoint) continue;  // PCSS takes no cube
      r.products = {Product::kVisibility, Product::kPosition};
      // The reference at the engine's points, with the oracle's normals.
      const RenderResult seen = engine.render(r);
      const Texture& pos = texture(seen, Product::kPosition);
      const oracle::CameraHits hits = oracle->cast_camera(r.camera);
      std::vector<glm::dvec3> points(hits.size());
      std::vector<uint8_t> receives(hits.size(), 1);
      for (size_t i = 0; i < hits.size(); ++i) {
        points[i] = glm::dvec3(pos.data[3 * i], pos.data[3 * i + 1], pos.data[3 * i + 2]);
        if (hits.hit(i)) receives[i] = sc.scene->instances[hits.instance[i]].receives_shadows;
      }
      const std::vector<float> expected =
          pcss ? oracle::area_visibility(*oracle, v.light, points, hits.normal, receives,
                                         {.tolerance = 0.02, .seen_side = true})
                     .visibility
               : oracle->hard_visibility(v.light, points, hits.normal, receives,
                                         {.seen_side = true});
      struct Case {
        Technique technique;
        uint32_t size;
        double bias;
      };
      std::vector<Case> cases;
      for (double b : biases) cases.push_back({Technique::kVirtual, 16384, b});
      // The dense maps the service offers for the light: uniform (a point light's cube) at
      // 2048^2 to 8192^2, PSM 1024^2, and LiSPSM 1024^2 for a sun.
      const Technique square =
          v.light.type == LightType::kPoint ? Technique::kCube : Technique::kUniform;
      if (dense) {
        for (uint32_t size : {2048u, 4096u, 8192u}) cases.push_back({square, size, 0});
        if (!pcss) cases.push_back({Technique::kPsm, 1024, 0});  // PCSS takes unwarped maps
        if (!pcss && v.light.type == LightType::kDirectional)
          cases.push_back({Technique::kLispsm, 1024, 0});
      }
      for (const Case& c : cases) {
        RenderRequest q = r;
        q.products = {Product::kVisibility};
        const bool picture =
            !pictures.empty() && c.technique == Technique::kVirtual && c.bias == biases.front();
        if (picture)
          q.products = {Product::kVisibility, Product::kPosition, Product::kVirtualPages};
        q.shadow_map.technique = c.technique;
        q.shadow_map.size = c.size;
        q.shadow_map.virtual_lod_bias = float(c.bias);
        RenderResult res;
        try {
          engine.render(q);  // warm: the timed render reuses nothing but the device's programs
          res = engine.render(q);
        } catch (const std::exception& e) {
          std::printf("%-28s %-9s %6u %+5.1f refused: %s\n", name.c_str(),
                      technique_label(c.technique), c.size, c.bias, e.what());
          continue;
        }
        Row row;
        row.view = name, row.technique = technique_label(c.technique);
        row.size = c.size, row.bias = c.bias;
        const oracle::VisibilityError error =
            oracle::compare_visibility(texture(res, Product::kVisibility).data, expected);
        row.misclassified = 100 * error.misclassified_rate();
        row.mae = error.mae, row.penumbra_mae = error.penumbra_mae;
        row.device_ms = device_ms(res);
        const Quote quote = engine.quote(q);  // admission's price, against the measured time
        row.estimate_ms = quote.ms, row.estimate_mib = quote.device_bytes / 1048576.0;
        if (res.virtual_pages) row.pages = *res.virtual_pages;
        if (picture) {  // name.<texture>.f32: width, height, channels (uint32), the floats, then
                        // world_to_camera (16 floats, column-major)
          std::string base = name;
          std::replace(base.begin(), base.end(), '/', '_');
          for (const Texture& t : res.textures) {
            if (t.name == "virtual_pool") continue;  // 64 MiB, not needed for the picture
            std::ofstream f(pictures + "/" + base + "." + t.name + ".f32", std::ios::binary);
            const uint32_t dims[3] = {t.width, t.height, t.channels};
            f.write(reinterpret_cast<const char*>(dims), sizeof dims);
            f.write(reinterpret_cast<const char*>(t.data.data()), t.data.size() * sizeof(float));
            f.write(reinterpret_cast<const char*>(&t.world_to_camera[0][0]), 16 * sizeof(float));
          }
        }
        std::printf("%-28s %-9s %6u %+5.1f %8.3f %9llu %9llu %8.0f %9.1f %9.1f %8.0f", name.c_str(),
                    row.technique.c_str(), c.size, c.bias, row.misclassified,
                    (unsigned long long)row.pages.requested, (unsigned long long)row.pages.resident,
                    row.pages.pool_bytes / 1048576.0, row.device_ms, row.estimate_ms,
                    row.estimate_mib);
        if (pcss) std::printf("   MAE %.4f, penumbra MAE %.4f", row.mae, row.penumbra_mae);
        std::printf("\n");
        if (passes)
          std::printf("    %-40s %8llu overlaps, %llu box pixels\n", "shadow_map",
                      (unsigned long long)res.light_fits[0].raster_overlaps,
                      (unsigned long long)res.light_fits[0].raster_box_pixels);
        if (passes)
          for (const PassTiming& t : res.timings)
            std::printf("    %-40s %8.2f ms\n", t.pass.c_str(), t.device_ms);
        std::fflush(stdout);
        rows.push_back(row);
      }
    }
  }
  if (!csv.empty()) {
    std::ofstream out(csv);
    out << "view,technique,size,bias,misclassified_pct,requested,resident,coarsened,pool_mib,"
           "device_ms,estimate_ms,estimate_mib"
        << (pcss ? ",mae,penumbra_mae\n" : "\n");
    for (const Row& r : rows) {
      out << r.view << ',' << r.technique << ',' << r.size << ',' << r.bias << ','
          << r.misclassified << ',' << r.pages.requested << ',' << r.pages.resident << ','
          << r.pages.coarsened_pixels << ',' << r.pages.pool_bytes / 1048576.0 << ',' << r.device_ms
          << ',' << r.estimate_ms << ',' << r.estimate_mib;
      if (pcss) out << ',' << r.mae << ',' << r.penumbra_mae;
      out << '\n';
    }
  }
  return 0;
}
