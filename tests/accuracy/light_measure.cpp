#include "light_measure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "shared_engine.hpp"

namespace shadow::accuracy {

scenes::Setup angled_setup(double angle_deg, double far_over_near, bool behind_wall) {
  scenes::Setup s = scenes::test_scene();
  s.camera.eye = {0, 6, 22};
  s.camera.target = {0, 0, 0};
  s.camera.width = 320;
  s.camera.height = 180;
  s.camera.far = 60;
  s.camera.near = float(60 / far_over_near);
  const glm::dvec3 f = glm::normalize(glm::dvec3(s.camera.target - s.camera.eye));
  // Rotate the view direction by the angle towards "down and to the side", so that the light
  // still reaches the ground at mid angles.
  const glm::dvec3 side =
      glm::normalize(glm::dvec3(0.4, -1, 0) - glm::dot(glm::dvec3(0.4, -1, 0), f) * f);
  const double a = glm::radians(angle_deg);
  s.light.direction = glm::vec3(glm::normalize(std::cos(a) * f + std::sin(a) * side));
  if (behind_wall)  // 60 m wide, 30 m high, 6 m behind the camera: its shadow reaches z ~ 5
    scenes::add(s.scene, scenes::box_mesh(), scenes::trs({0, 15, 28}, 0, {0, 1, 0}, {60, 30, 1}));
  return s;
}

Measured measure(const scenes::Setup& s, const oracle::RayOracle& oracle, Technique technique,
                 PsmCasters casters, uint32_t map_size, bool with_depth, const Tweak& tweak,
                 bool with_density) {
  RenderRequest req;
  req.scene = std::make_shared<Scene>(s.scene);
  req.camera = s.camera;
  req.lights = {s.light};
  req.shadow_map.size = map_size;
  req.shadow_map.technique = technique;
  req.shadow_map.psm.casters = casters;
  if (const char* b = std::getenv("PSM_SLOPE")) req.shadow_map.bias_slope = std::atof(b);
  if (const char* b = std::getenv("PSM_CONST")) req.shadow_map.bias_constant = std::atof(b);
  req.products = {Product::kShadowMap, Product::kVisibility, Product::kPosition};
  if (with_density) req.products.push_back(Product::kTexelDensity);
  if (tweak) tweak(req);
  const RenderResult r = engine().render(req);
  const Texture& map = texture(r, Product::kShadowMap);
  const Texture& vis = texture(r, Product::kVisibility);
  const Texture& pos = texture(r, Product::kPosition);
  Measured m;
  m.light_case = r.light_fits[0].light_case;
  m.fit = r.light_fits[0];
  // A point light's cube (TECHNIQUE_CUBE, or PSM's fallback) carries a matrix per face.
  const bool cube = !map.cube_faces.empty() || map.faces != 1;
  std::vector<glm::mat4> matrices = {map.world_to_ndc};
  if (cube) matrices.clear();
  for (const TextureFace& f : map.cube_faces) matrices.push_back(f.world_to_ndc);
  for (const glm::mat4& mat : matrices)
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) EXPECT_TRUE(std::isfinite(mat[c][k]));
  for (float v : map.data) EXPECT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 1.0f) << v;
  for (double v :
       {r.light_fits[0].virtual_near, r.light_fits[0].virtual_far, r.light_fits[0].light_near,
        r.light_fits[0].light_far, r.light_fits[0].slide_back})
    EXPECT_TRUE(std::isfinite(v));
  if (with_depth && !cube) {
    // The rasterizer draws only clip w > 0, which is where every caster of a visible receiver
    // is (the fit makes it so); the whole line's other half (w < 0) is not part of the map.
    oracle::DepthOptions o;
    o.require_positive_w = true;
    const auto expected = oracle.shadow_map_depth(glm::dmat4(map.world_to_ndc), map_size, o);
    m.depth = oracle::compare_depth(map.data, expected, 1e-5);
    if (std::getenv("PSM_DEPTH_DEBUG")) {
      const int n = int(map_size);
      size_t edge = 0, bad = 0, hist[6] = {};
      double dsum = 0;
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const size_t i = size_t(y) * n + x;
          const double err = std::abs(map.data[i] - expected[i]);
          if (err <= 1e-5) continue;
          ++bad;
          dsum += expected[i];
          hist[std::min(5, int(std::floor(-std::log10(err))))]++;
          bool e = false;
          for (auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= n || yy >= n) continue;
            e |= std::abs(expected[size_t(yy) * n + xx] - expected[i]) > 1e-3;
          }
          edge += e;
        }
      std::printf(
          "[ depthdbg ] bad %zu, at a reference depth edge %zu, mean ref depth %.4f, "
          "err 1e-0..1e-5: %zu %zu %zu %zu %zu %zu\n",
          bad, edge, bad ? dsum / bad : 0.0, hist[0], hist[1], hist[2], hist[3], hist[4], hist[5]);
    }
  }
  const oracle::CameraHits hits = oracle.cast_camera(s.camera);
  std::vector<glm::dvec3> points(hits.size()), normals(hits.size());
  std::vector<uint8_t> receives(hits.size(), 1);
  for (size_t i = 0; i < hits.size(); ++i) {
    points[i] = glm::dvec3(pos.data[3 * i], pos.data[3 * i + 1], pos.data[3 * i + 2]);
    normals[i] = hits.normal[i];
    if (hits.hit(i)) receives[i] = s.scene.instances[hits.instance[i]].receives_shadows;
  }
  const auto expected =
      oracle.hard_visibility(s.light, points, normals, receives, {.seen_side = true});
  for (float v : expected) m.shadowed += v < 0.5f;
  m.vis = oracle::compare_visibility(vis.data, expected);
  std::vector<double> distance(hits.size());
  for (size_t i = 0; i < hits.size(); ++i)
    distance[i] = glm::length(hits.position[i] - glm::dvec3(s.camera.eye));
  m.bands = oracle::compare_visibility_by_distance(vis.data, expected, distance,
                                                   oracle::kStandardDistanceEdges);
  for (size_t i = 0; i < expected.size(); ++i) {
    if (std::isnan(expected[i]) || std::isnan(vis.data[i])) continue;
    m.acne += vis.data[i] < 0.5f && expected[i] > 0.5f;
    m.leak += vis.data[i] > 0.5f && expected[i] < 0.5f;
  }
  if (with_density) {
    const Texture& density = texture(r, Product::kTexelDensity);
    std::vector<std::vector<double>> bands(3);
    for (size_t i = 0; i < hits.size(); ++i) {
      if (!hits.hit(i) || !std::isfinite(density.data[i])) continue;
      bands[distance[i] < 10 ? 0 : (distance[i] < 50 ? 1 : 2)].push_back(density.data[i]);
    }
    for (auto& b : bands) {
      if (b.empty()) {
        m.density_median.push_back(NAN);
        continue;
      }
      std::nth_element(b.begin(), b.begin() + b.size() / 2, b.end());
      m.density_median.push_back(b[b.size() / 2]);
    }
  }
  if (std::getenv("PSM_DEBUG")) {
    size_t acne = 0, leak = 0, near_miss = 0;
    for (size_t i = 0; i < expected.size(); ++i) {
      if (std::isnan(expected[i]) || std::isnan(vis.data[i])) continue;
      near_miss += (vis.data[i] < 0.5f) != (expected[i] < 0.5f) &&
                   glm::length(points[i] - glm::dvec3(s.camera.eye)) < 15.0;
      acne += vis.data[i] < 0.5f && expected[i] > 0.5f;
      leak += vis.data[i] > 0.5f && expected[i] < 0.5f;
    }
    std::printf(
        "[ debug    ] engine dark/oracle lit %zu, engine lit/oracle dark %zu, within 15 m %zu\n",
        acne, leak, near_miss);
  }
  return m;
}

std::string bands(const Measured& m) {
  std::string s;
  char buf[96];
  for (const oracle::DistanceBand& b : m.bands) {
    std::snprintf(buf, sizeof buf, "%s%s %.3f%% (%zu px)", s.empty() ? "" : ", ", b.label().c_str(),
                  100 * b.error.misclassified_rate(), b.error.both_valid);
    s += buf;
  }
  return s;
}

}  // namespace shadow::accuracy
