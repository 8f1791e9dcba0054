// virtual-page-study: how many 128x128 pages of a directional light's virtual clipmap (issue 53)
// the standard scenes' sun views would mark, against the LOD bias, before any of it is built.
// Levels are absolute: level l spans 2^l world units in N = 16384 texels, its window of 128 x 128
// pages centred on the camera's page. A pixel takes the level whose texel is at most its
// footprint in light space times 2^bias (its neighbours' light-space offsets; a depth jump falls
// back to the pixel's own world size), and marks the pages its PCF 2x2 taps read (a 1-texel
// margin). The engine renders POSITION; the study's per-pixel arithmetic runs on the host because
// it is a measurement, not the service.
#include <cmath>
#include <cstdio>
#include <set>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

#include "engine/engine.hpp"
#include "oracle/standard_scenes.hpp"

namespace {

using namespace shadow;

constexpr double kTexels = 16384, kPage = 128, kPagesPerLevel = kTexels / kPage;

struct Basis {
  glm::dvec3 u, v;
};

Basis light_basis(const glm::dvec3& travel) {
  const glm::dvec3 d = glm::normalize(travel);
  const glm::dvec3 up = std::abs(d.y) < 0.99 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
  const glm::dvec3 u = glm::normalize(glm::cross(up, d));
  return {u, glm::cross(d, u)};
}

size_t pages(const std::vector<float>& pos, uint32_t w, uint32_t h, const Camera& cam,
             const Basis& b, double bias, int* finest, int* coarsest) {
  const glm::dvec3 eye(cam.eye);
  const double pixel_angle = 2 * std::tan(glm::radians(double(cam.fov_deg)) / 2) / h;
  const glm::dvec2 eye_ls(glm::dot(eye, b.u), glm::dot(eye, b.v));
  const auto at = [&](uint32_t x, uint32_t y) {
    const float* p = &pos[(size_t(y) * w + x) * 3];
    return glm::dvec3(p[0], p[1], p[2]);
  };
  std::set<std::tuple<int, int64_t, int64_t>> marked;
  *finest = 99, *coarsest = -99;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const glm::dvec3 p = at(x, y);
      if (!std::isfinite(p.x)) continue;
      const double s = glm::length(p - eye) * pixel_angle;  // the pixel's own world size
      double f = 0;
      for (const auto& [nx, ny] : {std::pair{x + 1, y}, std::pair{x, y + 1}}) {
        if (nx >= w || ny >= h) continue;
        const glm::dvec3 q = at(nx, ny);
        if (!std::isfinite(q.x) || glm::length(q - p) > 4 * s) continue;  // a depth jump
        const glm::dvec3 d = q - p;
        f = std::max(f, std::max(std::abs(glm::dot(d, b.u)), std::abs(glm::dot(d, b.v))));
      }
      if (f == 0) f = s;
      const glm::dvec2 ls(glm::dot(p, b.u), glm::dot(p, b.v));
      int level = int(std::floor(std::log2(f * std::exp2(bias) * kTexels)));
      for (;; ++level) {  // the first level whose window holds the point
        const double page = std::exp2(level) / kTexels * kPage;
        const glm::dvec2 rel = (ls - eye_ls) / page;
        if (std::abs(rel.x) < kPagesPerLevel / 2 - 1 && std::abs(rel.y) < kPagesPerLevel / 2 - 1)
          break;
      }
      *finest = std::min(*finest, level), *coarsest = std::max(*coarsest, level);
      const double texel = std::exp2(level) / kTexels, page = texel * kPage;
      for (int dy = -1; dy <= 1; dy += 2)
        for (int dx = -1; dx <= 1; dx += 2)
          marked.emplace(level, int64_t(std::floor((ls.x + dx * texel) / page)),
                         int64_t(std::floor((ls.y + dy * texel) / page)));
    }
  return marked.size();
}

}  // namespace

int main() {
  EngineOptions options;
  options.max_request_cost_ms = 0;
  Engine engine(options);
  const double biases[] = {-1, -0.5, 0, 0.5, 1};
  std::printf("%-28s %8s", "scene/view (1280x720)", "levels");
  for (double b : biases) std::printf("  bias %+4.1f", b);
  std::printf("\n");
  for (const scenes::StandardScene& sc : scenes::standard_scenes())
    for (const scenes::View& v : sc.views) {
      if (v.light.type != LightType::kDirectional) continue;
      RenderRequest r;
      r.scene = sc.scene;
      r.camera = v.camera;
      r.camera.width = 1280, r.camera.height = 720;
      r.lights = {v.light};
      r.products = {Product::kPosition};
      const RenderResult res = engine.render(r);
      const Basis b = light_basis(glm::dvec3(v.light.direction));
      std::printf("%-28s", (sc.name + "/" + v.name).c_str());
      std::string counts;
      int lo = 0, hi = 0;
      for (double bias : biases) {
        char cell[32];
        std::snprintf(cell, sizeof cell, "  %9zu",
                      pages(res.textures[0].data, 1280, 720, r.camera, b, bias, &lo, &hi));
        counts += cell;
      }
      std::printf(" %3d..%-3d%s\n", lo, hi, counts.c_str());
    }
  return 0;
}
