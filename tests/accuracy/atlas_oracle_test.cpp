// Shadow atlases against independent references, on a ground and two boxes whose six faces are
// each their own chart (the faces turned away from the light and from any camera included):
// - the bake's coverage and world positions against a double-precision rasterization of the
//   same UV triangles (barycentric evaluation, square/triangle overlap by separating axes);
// - the baked hard shadow against Embree shadow rays from the same world points.
// Bounds are the figures measured on PoCL's CPU backend with a small margin; every run prints
// them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/passes/atlas.hpp"
#include "engine/passes/rasterizer.hpp"
#include "oracle/area_light.hpp"
#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/standard_scenes.hpp"
#include "shared_engine.hpp"

namespace shadow {
namespace {

// A cube [-1, 1]^3 whose face k has the chart at cell (k % 3, k / 3) of a 3 x 2 grid of the UV
// square, inset by 0.02 so the charts' gutters do not meet. Outward counter-clockwise winding.
Mesh unwrapped_box() {
  Mesh m;
  for (int k = 0; k < 6; ++k) {
    const int a = k / 2;
    const float sign = k % 2 ? -1.0f : 1.0f;
    int b = (a + 1) % 3, c = (a + 2) % 3;
    if (sign < 0) std::swap(b, c);  // e_b x e_c points out of the face
    const glm::vec2 cell(float(k % 3) / 3.0f, float(k / 3) / 2.0f);
    const glm::vec2 span(1.0f / 3.0f - 0.04f, 0.5f - 0.04f);
    const uint32_t base = uint32_t(m.vertex_count());
    for (glm::vec2 st : {glm::vec2(0, 0), glm::vec2(1, 0), glm::vec2(1, 1), glm::vec2(0, 1)}) {
      glm::vec3 p(0.0f);
      p[a] = sign, p[b] = 2 * st.x - 1, p[c] = 2 * st.y - 1;
      m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
      const glm::vec2 uv = cell + glm::vec2(0.02f) + st * span;
      m.uvs.insert(m.uvs.end(), {uv.x, uv.y});
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  return m;
}

// A 24 m ground at y = 0 whose UVs span the whole tile.
Mesh ground() {
  Mesh m;
  m.positions = {-12, 0, -12, 12, 0, -12, 12, 0, 12, -12, 0, 12};
  m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  m.indices = {0, 2, 1, 0, 3, 2};  // facing up
  return m;
}

RenderRequest atlas_request() {
  auto scene = std::make_shared<Scene>();
  scene->meshes = {ground(), unwrapped_box()};
  Instance floating{1}, tilted{1};
  floating.transform = glm::translate(glm::mat4(1.0f), glm::vec3(0.5f, 2.0f, -1.0f));
  tilted.transform = glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(-5, 1.8f, 4)),
                                            0.6f, glm::normalize(glm::vec3(1, 1, 0))),
                                glm::vec3(1.5f, 0.7f, 1.0f));
  scene->instances = {Instance{0}, floating, tilted};
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 15, 20};
  r.camera.target = {0, 0, 0};
  Light sun;
  sun.type = LightType::kDirectional;
  sun.direction = glm::normalize(glm::vec3(0.35f, -1.0f, 0.25f));
  r.lights = {sun};
  r.shadow_map.size = 2048;
  r.shadow_map.fit = MapFit::kScene;
  r.products = {Product::kShadowAtlas};
  r.atlas.tile = 256;
  r.atlas.gutter = 2;
  return r;
}

double cross2(glm::dvec2 a, glm::dvec2 b, glm::dvec2 q) {
  return (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
}

// Whether the square [x - g, x + 1 + g] x [y - g, y + 1 + g] and triangle p overlap with
// positive area: no separating axis among the square's two and the triangle's edge normals.
bool square_meets_triangle(double x, double y, double g, const glm::dvec2 p[3]) {
  const glm::dvec2 corners[4] = {
      {x - g, y - g}, {x + 1 + g, y - g}, {x - g, y + 1 + g}, {x + 1 + g, y + 1 + g}};
  std::vector<glm::dvec2> axes = {{1, 0}, {0, 1}};
  for (int k = 0; k < 3; ++k) {
    const glm::dvec2 e = p[(k + 1) % 3] - p[k];
    axes.push_back({-e.y, e.x});
  }
  for (const glm::dvec2& n : axes) {
    double a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
    for (const glm::dvec2& c : corners)
      a0 = std::min(a0, glm::dot(n, c)), a1 = std::max(a1, glm::dot(n, c));
    for (int k = 0; k < 3; ++k)
      b0 = std::min(b0, glm::dot(n, p[k])), b1 = std::max(b1, glm::dot(n, p[k]));
    if (a1 <= b0 || b1 <= a0) return false;
  }
  return true;
}

// What a double-precision rasterization of the UV triangles says about one atlas texel.
struct ReferenceTexel {
  bool touched = false;        // some triangle overlaps the texel's square
  bool ambiguous = false;      // within 1e-4 texel of touching, or of a triangle edge
  bool centre_inside = false;  // the centre lies strictly inside a triangle (by 1e-4 texel)
  glm::dvec3 position{NAN}, normal{NAN};  // world, where centre_inside
};

std::vector<ReferenceTexel> reference_bake(const Scene& scene, const std::vector<AtlasTile>& tiles,
                                           uint32_t width, uint32_t height) {
  std::vector<ReferenceTexel> out(size_t{width} * height);
  constexpr double kMargin = 1e-4;
  for (const AtlasTile& tile : tiles) {
    const Instance& inst = scene.instances[tile.instance];
    const Mesh& m = scene.meshes[inst.mesh];
    const glm::dmat4 to_world(inst.transform);
    for (size_t i = 0; i < m.indices.size(); i += 3) {
      glm::dvec2 p[3];
      glm::dvec3 w[3];
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.indices[i + k];
        p[k] = glm::dvec2(tile.x, tile.y) +
               glm::dvec2(m.uvs[2 * v], m.uvs[2 * v + 1]) * double(tile.size);
        w[k] = glm::dvec3(to_world * glm::dvec4(m.positions[3 * v], m.positions[3 * v + 1],
                                                m.positions[3 * v + 2], 1.0));
      }
      const double area = cross2(p[0], p[1], p[2]);
      glm::dvec3 n = glm::normalize(glm::cross(w[1] - w[0], w[2] - w[0]));
      const int x0 = std::max(int(tile.x), int(std::floor(std::min({p[0].x, p[1].x, p[2].x}))) - 1);
      const int y0 = std::max(int(tile.y), int(std::floor(std::min({p[0].y, p[1].y, p[2].y}))) - 1);
      const int x1 =
          std::min(int(tile.x + tile.size) - 1, int(std::ceil(std::max({p[0].x, p[1].x, p[2].x}))));
      const int y1 =
          std::min(int(tile.y + tile.size) - 1, int(std::ceil(std::max({p[0].y, p[1].y, p[2].y}))));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          ReferenceTexel& r = out[size_t(y) * width + x];
          // The square grown and shrunk by the margin disagree: too close to call.
          r.ambiguous |=
              square_meets_triangle(x, y, kMargin, p) != square_meets_triangle(x, y, -kMargin, p);
          if (square_meets_triangle(x, y, 0, p)) r.touched = true;
          const glm::dvec2 c(x + 0.5, y + 0.5);
          const glm::dvec3 l =
              glm::dvec3(cross2(p[1], p[2], c), cross2(p[2], p[0], c), cross2(p[0], p[1], c)) /
              area;
          // Distance in texels from the centre to each edge: l_k times the opposite height.
          double nearest = INFINITY;
          for (int k = 0; k < 3; ++k)
            nearest = std::min(nearest, std::abs(cross2(p[(k + 1) % 3], p[(k + 2) % 3], c)) /
                                            glm::length(p[(k + 2) % 3] - p[(k + 1) % 3]));
          const bool inside = l.x > 0 && l.y > 0 && l.z > 0;
          if (inside && nearest > kMargin) {
            r.centre_inside = true;
            r.position = l.x * w[0] + l.y * w[1] + l.z * w[2];
            r.normal = n;
          } else if (nearest <= kMargin) {
            r.ambiguous = true;
          }
        }
    }
  }
  return out;
}

// The bake itself, without the engine: every texel whose centre a UV triangle holds gets that
// triangle's point, texels no triangle touches stay empty, and thin or partial texels get a
// point too (conservative coverage).
TEST(AtlasOracle, BakeCoversAndPlacesLikeADoubleRasterization) {
  const RenderRequest req = atlas_request();
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  AtlasPass pass(runtime, kernels);
  Timeline timeline;
  SceneBuffers buffers(runtime, kernels, *req.scene, timeline);
  const GBuffer& view = pass.bake(*req.scene, buffers, req.atlas, timeline);
  const uint32_t w = pass.width(), h = pass.height(), texels = w * h;
  std::vector<float> position(size_t{texels} * 3), normal(size_t{texels} * 4);
  runtime.read(view.position, position.data(), position.size() * sizeof(float));
  runtime.read(view.normal, normal.data(), normal.size() * sizeof(float));
  runtime.finish();
  const std::vector<ReferenceTexel> ref = reference_bake(*req.scene, pass.tiles(), w, h);

  size_t inside = 0, edge_only = 0, missed = 0, stray = 0;
  double worst_position = 0, worst_normal = 0;
  for (uint32_t t = 0; t < texels; ++t) {
    const ReferenceTexel& r = ref[t];
    const bool baked = !std::isnan(position[3 * t]);
    if (r.ambiguous) continue;
    if (r.touched != baked) {
      (r.touched ? missed : stray) += 1;
      if (missed + stray <= 5)
        std::printf("[ atlas    ] texel (%u, %u): reference %s, bake %s\n", t % w, t / w,
                    r.touched ? "touched" : "empty", baked ? "a point" : "empty");
      continue;
    }
    if (!r.centre_inside) {
      edge_only += baked;
      continue;
    }
    ++inside;
    const glm::dvec3 p(position[3 * t], position[3 * t + 1], position[3 * t + 2]);
    const glm::dvec3 n(normal[4 * t], normal[4 * t + 1], normal[4 * t + 2]);
    worst_position = std::max(worst_position, glm::length(p - r.position));
    worst_normal = std::max(worst_normal, glm::length(n - r.normal));
  }
  std::printf(
      "[ atlas    ] %ux%u: %zu texels inside a chart, %zu touched only; %zu missed, %zu "
      "stray; worst position error %.3g m, normal %.3g\n",
      w, h, inside, edge_only, missed, stray, worst_position, worst_normal);
  EXPECT_EQ(missed, 0u);
  EXPECT_EQ(stray, 0u);
  EXPECT_GT(edge_only, 0u);  // the charts' borders are partial texels, and kept
  // Measured 1.3e-6 m (float barycentrics over a 24 m ground) and 2.6e-7.
  EXPECT_LT(worst_position, 3e-6);
  EXPECT_LT(worst_normal, 1e-6);
}

// What HardShadowsMatchShadowRays counts of the misclassified texels.
struct HardMisses {
  size_t near_edge = 0, leak = 0, elsewhere = 0, shadowed = 0, points = 0;
  double farthest_leak = 0;
  oracle::VisibilityError error;
};

// The engine's baked hard shadow (req: one light) against Embree shadow rays from the
// reference's world points, including the boxes' undersides and far faces that no camera in the
// request sees. Misclassified texels are sorted by where they are: within 2 texels of the
// oracle's shadow edge in the atlas, or on a face turned from the light whose shadow ray meets a
// caster within 0.25 m (the bias hides such thin occluders: the light leaks around the boxes'
// terminator edges), or elsewhere.
HardMisses hard_against_rays(const RenderRequest& req) {
  const RenderResult result = accuracy::engine().render(req);
  const Texture& atlas = accuracy::texture(result, Product::kShadowAtlas);
  const std::vector<ReferenceTexel> ref =
      reference_bake(*req.scene, atlas.atlas_tiles, atlas.width, atlas.height);
  std::vector<glm::dvec3> points, normals;
  std::vector<float> engine;
  std::vector<size_t> texel;
  for (size_t t = 0; t < ref.size(); ++t) {
    if (!ref[t].centre_inside || ref[t].ambiguous) continue;
    points.push_back(ref[t].position);
    normals.push_back(ref[t].normal);
    engine.push_back(atlas.data[t]);
    texel.push_back(t);
  }
  const oracle::RayOracle rays(*req.scene);
  const Light& light = req.lights[0];
  const std::vector<float> want = rays.hard_visibility(light, points, normals);
  HardMisses m;
  m.error = oracle::compare_visibility(engine, want);
  m.points = points.size();
  std::vector<float> oracle_at(ref.size(), NAN);
  for (size_t k = 0; k < texel.size(); ++k) oracle_at[texel[k]] = want[k];
  constexpr double kReach = 0.25;  // metres
  for (size_t k = 0; k < texel.size(); ++k) {
    if (std::abs(engine[k] - want[k]) <= 0.5f) continue;
    const int x = int(texel[k] % atlas.width), y = int(texel[k] / atlas.width);
    bool edge = false;
    for (int j = std::max(y - 2, 0); j <= std::min(y + 2, int(atlas.height) - 1); ++j)
      for (int i = std::max(x - 2, 0); i <= std::min(x + 2, int(atlas.width) - 1); ++i) {
        const float o = oracle_at[size_t(j) * atlas.width + i];
        edge |= !std::isnan(o) && o != want[k];
      }
    const glm::dvec3 to_light = light.type == LightType::kDirectional
                                    ? -glm::normalize(glm::dvec3(light.direction))
                                    : glm::normalize(glm::dvec3(light.position) - points[k]);
    const double facing = glm::dot(normals[k], to_light);
    const glm::dvec3 origin = points[k] + (facing < 0 ? -1.0 : 1.0) * 1e-4 * normals[k];
    if (edge) {
      ++m.near_edge;
    } else if (facing < 0 && rays.occluded(origin, to_light, kReach)) {
      ++m.leak;
      double lo = 0, hi = kReach;  // the nearest occluder's distance, by bisection
      for (int i = 0; i < 30; ++i) {
        const double mid = 0.5 * (lo + hi);
        (rays.occluded(origin, to_light, mid) ? hi : lo) = mid;
      }
      m.farthest_leak = std::max(m.farthest_leak, hi);
    } else if (++m.elsewhere <= 5) {
      std::printf("[ atlas    ] misclassified texel (%d, %d): engine %g, oracle %g\n", x, y,
                  engine[k], want[k]);
    }
  }
  for (float v : want) m.shadowed += v < 0.5f;
  std::printf(
      "[ atlas    ] misclassified: %zu near shadow edges, %zu light leaks through "
      "occluders at most %.3f m away, %zu elsewhere\n",
      m.near_edge, m.leak, m.farthest_leak, m.elsewhere);
  std::printf("[ atlas    ] %zu texels (%zu shadowed by the oracle): %s\n", m.points, m.shadowed,
              m.error.summary().c_str());
  EXPECT_EQ(m.error.nan_mismatch, 0u);
  EXPECT_GT(m.shadowed, m.points / 10);  // the scene does cast shadows into the atlas
  return m;
}

TEST(AtlasOracle, HardShadowsMatchShadowRays) {
  const HardMisses m = hard_against_rays(atlas_request());
  // Measured with attached shadows (faces turned from the light are dark whatever the bias):
  // 6 near edges, no leaks, 0.0035% in all.
  EXPECT_EQ(m.elsewhere, 0u);
  EXPECT_LT(m.farthest_leak, 0.2);
  EXPECT_LT(m.error.misclassified_rate(), 9.4e-5);
}

// A point light's atlas: its cube's faces fitted to every receiver (MAP_FIT_SCENE), each texel
// tested in the face that owns it. The camera looks away from the scene: faces fitted to its
// view would render nothing.
TEST(AtlasOracle, PointLightHardShadowsMatchShadowRays) {
  RenderRequest req = atlas_request();
  Light bulb;
  bulb.type = LightType::kPoint;
  bulb.position = {2.3f, 6.0f, 0.7f};
  req.lights = {bulb};
  req.shadow_map.size = 1024;
  req.camera.target = {0, 30, 40};
  const HardMisses m = hard_against_rays(req);
  // Measured with attached shadows against Embree with a 1e-6 ray offset: 34 near edges, no
  // leaks, 0.020% in all (2048 faces: 0.0035%). A face whose plane holds the light (edge-on) is
  // misclassified wholesale: the light avoids the boxes' planes.
  EXPECT_EQ(m.elsewhere, 0u);
  EXPECT_LT(m.farthest_leak, 0.15);
  EXPECT_LT(m.error.misclassified_rate(), 2.6e-4);
}

// Soft shadows through the atlas (FILTER_ATLAS_SAT, FILTER_ATLAS_MIP) and PCSS against the
// Embree area-light oracle, the camera's view of the boxes and their shadows under an 8-degree
// sun.
TEST(AtlasOracle, SoftShadowsAgainstTheAreaLight) {
  RenderRequest req = atlas_request();
  req.camera.eye = {4, 7, 7};
  req.camera.target = {-1, 1, 0};
  req.camera.width = 480, req.camera.height = 270;
  req.lights[0].size = 8.0f;
  req.atlas.tile = 512;
  req.products = {Product::kVisibility};
  const oracle::RayOracle rays(*req.scene);
  const oracle::AreaVisibility truth =
      oracle::camera_area_visibility(rays, req.camera, req.lights[0]);
  std::map<FilterKind, oracle::VisibilityError> errors;
  for (FilterKind kind : {FilterKind::kPcss, FilterKind::kAtlasSat, FilterKind::kAtlasMip}) {
    req.filter.kind = kind;
    const RenderResult r = accuracy::engine().render(req);
    const oracle::VisibilityError e = oracle::compare_visibility(
        accuracy::texture(r, Product::kVisibility).data, truth.visibility);
    std::printf("[ atlas    ] %s: %s, penumbra MAE %.4f over %zu pixels\n",
                kind == FilterKind::kPcss       ? "pcss"
                : kind == FilterKind::kAtlasSat ? "atlas_sat"
                                                : "atlas_mip",
                e.summary().c_str(), e.penumbra_mae, e.penumbra_pixels);
    EXPECT_EQ(e.nan_mismatch, 0u);
    errors[kind] = e;
  }
  EXPECT_EQ(truth.unconverged, 0u);
  EXPECT_GT(errors[FilterKind::kPcss].penumbra_pixels, 500u);  // the view has penumbrae
  // Measured with the footprint as an ellipse: MAE 0.0018 / 0.0013 / 0.0019 and penumbra MAE
  // 0.052 / 0.034 / 0.048 for PCSS, atlas_sat and atlas_mip over 2 204 penumbra pixels (with
  // l_lod's disk they were 0.0030 / 0.0072 and 0.073 / 0.110 for the atlas filters); 1 of 87613
  // pixels misclassified each.
  EXPECT_LT(errors[FilterKind::kAtlasSat].mae, 0.0015);
  EXPECT_LT(errors[FilterKind::kAtlasMip].mae, 0.0021);
  EXPECT_LT(errors[FilterKind::kAtlasSat].penumbra_mae, 0.038);
  EXPECT_LT(errors[FilterKind::kAtlasMip].penumbra_mae, 0.053);
  for (const auto& [kind, e] : errors) EXPECT_LT(e.misclassified_rate(), 1.3e-4);
}

// The atlas filters on every standard scene whose light the atlas takes (uniform maps: all but
// the room's point lights), each scene's overview at 640x360 with a 2048 map fitted to the scene
// and the default atlas density (each instance's tile from the map's texel footprint on it),
// every receiving mesh laid out by the server (generate_uvs: the scenes' own UVs tile), against
// the area-light oracle, with PCSS and the hard test beside them: the mean error, over the
// penumbra (0.02 < oracle < 0.98), and over the pixels the oracle sees fully lit. The bounds are
// the figures measured on PoCL's CPU backend (shadow-atlas-bench --standard --tile 0,
// docs/benchmarks.md, "Shadow atlases") plus 10% and 2e-4, the run-to-run spread of the rotated
// blocker patterns being far below that. Issue 43's goals, per scene over its views: the atlas
// filters' mean error within 1.5x PCSS's, their error on fully lit pixels within PCSS's + 0.002,
// their penumbra error under the hard test's; docs/benchmarks.md has every view.
struct Figures {
  double mae, penumbra, lit;
};
struct SceneBounds {
  scenes::StandardScene scene;
  std::string view;
  Figures hard, pcss, sat, mip;  // measured
};

TEST(AtlasOracle, SoftShadowsOnStandardScenes) {
  const auto bound = [](double measured) { return measured * 1.1 + 2e-4; };
  // The forest's generated layouts and 601 tiles are estimated over the default request cost.
  static Engine engine = [] {
    EngineOptions options;
    options.max_request_cost_ms = 0;
    return Engine(options);
  }();
  for (const SceneBounds& row : {
           // Measured (mean error, penumbra, fully lit): hard, PCSS, atlas_sat, atlas_mip.
           SceneBounds{scenes::chess(),
                       "overview",
                       {0.0010, 0.181, 0.0001},
                       {0.0004, 0.064, 0.0001},
                       {0.0016, 0.218, 0.0007},
                       {0.0016, 0.219, 0.0007}},
           // A sun 7 degrees over the board: the footprint stretched along it, capped at 8.
           SceneBounds{scenes::chess(),
                       "grazing",
                       {0.0059, 0.259, 0.0000},
                       {0.0065, 0.096, 0.0035},
                       {0.0070, 0.077, 0.0049},
                       {0.0071, 0.077, 0.0049}},
           SceneBounds{scenes::street(),
                       "overview",
                       {0.0118, 0.377, 0.0042},
                       {0.0121, 0.249, 0.0066},
                       {0.0134, 0.219, 0.0088},
                       {0.0134, 0.219, 0.0088}},
           SceneBounds{scenes::forest(),
                       "overview",
                       {0.0112, 0.381, 0.0024},
                       {0.0112, 0.252, 0.0039},
                       {0.0124, 0.274, 0.0045},
                       {0.0124, 0.272, 0.0045}},
           SceneBounds{scenes::resting(),
                       "overview",
                       {0.0003, 0.419, 0.0001},
                       {0.0005, 0.216, 0.0002},
                       {0.0007, 0.280, 0.0003},
                       {0.0007, 0.280, 0.0003}},
           SceneBounds{scenes::heights(),
                       "overview",
                       {0.0007, 0.263, 0.0000},
                       {0.0003, 0.064, 0.0001},
                       {0.0004, 0.080, 0.0002},
                       {0.0004, 0.085, 0.0002}},
           // The sun along the street: its facades are edge-on, in the hard test's attached
           // shadow, the area light's half above their horizon. The atlas filters leave such
           // texels out and cap by the horizon per pixel (before: 0.046 / 0.114 MAE, their
           // tiles' other faces averaged in).
           SceneBounds{scenes::street(),
                       "light_behind_camera",
                       {0.2152, 0.498, 0.0000},
                       {0.0352, 0.078, 0.0003},
                       {0.0022, 0.0025, 0.0011},
                       {0.0022, 0.0025, 0.0011}},
       }) {
    const scenes::View& view = scenes::find_view(row.scene, row.view);
    RenderRequest req;
    req.scene = row.scene.scene;
    req.camera = view.camera;
    req.lights = {view.light};
    req.shadow_map.fit = MapFit::kScene;
    req.atlas.generate_uvs = true;  // and the default density
    req.products = {Product::kVisibility};
    const oracle::RayOracle rays(*req.scene);
    const oracle::AreaVisibility truth =
        oracle::camera_area_visibility(rays, req.camera, req.lights[0]);
    EXPECT_EQ(truth.unconverged, 0u);
    for (const auto& [kind, name, want] : {std::tuple{FilterKind::kHard, "hard", row.hard},
                                           {FilterKind::kPcss, "pcss", row.pcss},
                                           {FilterKind::kAtlasSat, "atlas_sat", row.sat},
                                           {FilterKind::kAtlasMip, "atlas_mip", row.mip}}) {
      req.filter.kind = kind;
      const std::vector<float> got =
          accuracy::texture(engine.render(req), Product::kVisibility).data;
      const oracle::VisibilityError e = oracle::compare_visibility(got, truth.visibility);
      double lit = 0;
      size_t lit_pixels = 0;
      for (size_t p = 0; p < got.size(); ++p)
        if (truth.visibility[p] == 1.0f && std::isfinite(got[p]))
          lit += std::abs(1.0 - got[p]), ++lit_pixels;
      lit /= double(std::max<size_t>(lit_pixels, 1));
      std::printf(
          "[ atlas    ] %s / %s, %s: MAE %.4f, penumbra MAE %.4f over %zu pixels, lit "
          "error %.4f over %zu pixels\n",
          row.scene.name.c_str(), view.name.c_str(), name, e.mae, e.penumbra_mae, e.penumbra_pixels,
          lit, lit_pixels);
      // At most one silhouette pixel that the camera's raster and Embree see differently (the
      // forest's overview has one, whatever the filter).
      EXPECT_LE(e.nan_mismatch, 1u) << row.scene.name << ", " << name;
      EXPECT_GT(e.penumbra_pixels, 50u) << row.scene.name;  // the views have penumbrae
      EXPECT_LT(e.mae, bound(want.mae)) << row.scene.name << ", " << name;
      EXPECT_LT(e.penumbra_mae, bound(want.penumbra)) << row.scene.name << ", " << name;
      EXPECT_LT(lit, bound(want.lit)) << row.scene.name << ", " << name;
    }
  }
}

}  // namespace
}  // namespace shadow
