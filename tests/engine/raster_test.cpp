// The rasterizer kernels against exact CPU references: coverage and the fill rule, depth
// interpolation, and homogeneous clipping (a double-precision ray cast per pixel).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/passes/rasterizer.hpp"

namespace shadow {
namespace {

struct Device {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  Rasterizer rasterizer{runtime, kernels};
};

Device& device() {
  static Device d;
  return d;
}

struct Raster {
  std::vector<float> depth;
  std::vector<uint32_t> ids;
};

// Rasterizes every triangle of `scene` (one instance per mesh) through `world_to_ndc`.
Raster rasterize(const Scene& scene, const glm::mat4& world_to_ndc, uint32_t w, uint32_t h) {
  Device& d = device();
  Timeline timeline;
  SceneBuffers buffers(d.runtime, d.kernels, scene, timeline);
  auto draws = make_draws(scene, buffers, world_to_ndc, [](const Instance&) { return true; });
  const RasterOutput& out = d.rasterizer.run(buffers, draws, w, h, true, "test", "test", timeline);
  Raster r{std::vector<float>(size_t{w} * h), std::vector<uint32_t>(size_t{w} * h)};
  d.runtime.read(out.depth, r.depth.data(), r.depth.size() * sizeof(float));
  d.runtime.read(out.ids, r.ids.data(), r.ids.size() * sizeof(uint32_t));
  return r;
}

Scene one_mesh(std::vector<float> positions, std::vector<uint32_t> indices) {
  Scene s;
  s.meshes.push_back(Mesh{std::move(positions), std::move(indices), {}, {}});
  s.instances.push_back(Instance{});
  return s;
}

// World x, y in pixels map to the viewport; world z is the depth.
glm::mat4 pixel_space(uint32_t w, uint32_t h) {
  return glm::scale(glm::mat4(1.0f), glm::vec3(1.0f / w, 1.0f / h, 1.0f));
}

// A fan of triangles around a vertex on a pixel centre, plus a grid whose edges run through
// pixel centres horizontally, vertically and diagonally: every pixel centre inside the square
// must be covered exactly once, and none outside.
TEST(Raster, SharedEdgesAreNeitherDoubleCoveredNorHoled) {
  const uint32_t n = 48;
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  const float lo = 4.5f, step = 4.0f;  // vertices on pixel centres
  const int cells = 9;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) pos.insert(pos.end(), {lo + i * step, lo + j * step, 0.5f});
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      uint32_t a = j * (cells + 1) + i, b = a + 1, c = a + cells + 1, d = c + 1;
      if ((i + j) % 2)
        idx.insert(idx.end(), {a, b, d, a, d, c});
      else
        idx.insert(idx.end(), {a, b, c, b, d, c});  // alternate the diagonal's direction
    }
  std::vector<int> coverage(n * n, 0);
  for (size_t t = 0; t < idx.size() / 3; ++t) {
    Scene s = one_mesh(pos, {idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]});
    Raster r = rasterize(s, pixel_space(n, n), n, n);
    for (size_t p = 0; p < coverage.size(); ++p) coverage[p] += r.ids[p] != 0xffffffffu;
  }
  const float hi = lo + cells * step;
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      float cx = x + 0.5f, cy = y + 0.5f;
      // Of the square's own boundary, the top and left edges are in, bottom and right are out.
      bool inside = cx >= lo && cx < hi && cy >= lo && cy < hi;
      ASSERT_EQ(coverage[y * n + x], inside ? 1 : 0) << "pixel " << x << "," << y;
    }
}

// The top-left rule on single triangles with edges through pixel centres, both windings.
TEST(Raster, TopLeftRuleOnATriangle) {
  const uint32_t n = 16;
  // Right triangle with a top edge (y = 2.5) and a left edge (x = 2.5) through pixel centres.
  for (bool flip : {false, true}) {
    std::vector<uint32_t> idx =
        flip ? std::vector<uint32_t>{0, 2, 1} : std::vector<uint32_t>{0, 1, 2};
    Scene s = one_mesh({2.5f, 2.5f, 0.5f, 10.5f, 2.5f, 0.5f, 2.5f, 10.5f, 0.5f}, idx);
    Raster r = rasterize(s, pixel_space(n, n), n, n);
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x) {
        int dx = int(x) - 2, dy = int(y) - 2;  // pixel centre offset from the right-angle vertex
        bool inside = dx >= 0 && dy >= 0 && dx + dy < 8;  // hypotenuse is a bottom-right edge
        EXPECT_EQ(r.ids[y * n + x] != 0xffffffffu, inside) << x << "," << y << " flip " << flip;
      }
  }
}

// Depth at every covered pixel centre equals the triangle's plane evaluated in double.
TEST(Raster, DepthInterpolationMatchesThePlane) {
  const uint32_t n = 256;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> xy(-20.0f, n + 20.0f), z(0.05f, 0.95f);
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  for (uint32_t t = 0; t < 200; ++t) {
    for (int k = 0; k < 3; ++k) pos.insert(pos.end(), {xy(rng), xy(rng), z(rng)});
    idx.insert(idx.end(), {3 * t, 3 * t + 1, 3 * t + 2});
  }
  Scene s = one_mesh(pos, idx);
  Raster r = rasterize(s, pixel_space(n, n), n, n);
  size_t checked = 0;
  double worst = 0.0;
  for (uint32_t p = 0; p < n * n; ++p) {
    uint32_t t = r.ids[p];
    if (t == 0xffffffffu) continue;
    ASSERT_LT(t, 200u);
    // The plane through the vertices as the rasterizer sees them: snapped to 1/256 pixel.
    auto vertex = [&](int k) {
      const float* v = &pos[9 * t + 3 * k];
      return glm::dvec3(std::nearbyint(v[0] * 256.0) / 256.0, std::nearbyint(v[1] * 256.0) / 256.0,
                        v[2]);
    };
    glm::dvec3 a = vertex(0), b = vertex(1), c = vertex(2);
    glm::dvec3 nrm = glm::cross(b - a, c - a);
    double px = p % n + 0.5, py = p / n + 0.5;
    double zr = a.z - (nrm.x * (px - a.x) + nrm.y * (py - a.y)) / nrm.z;
    worst = std::max(worst, std::abs(zr - r.depth[p]));
    ++checked;
  }
  EXPECT_GT(checked, n * n / 2);
  EXPECT_LT(worst, 2e-6) << "worst depth error";
}

// Nearest hit along the line through texture point (u, v), in double: the clipping reference.
struct RayCast {
  double depth = 1.0;
  int triangle = -1;
};

RayCast ray_cast(const std::vector<glm::dvec3>& tris, const glm::dmat4& m, double u, double v) {
  glm::dmat4 inv = glm::inverse(m);
  glm::dvec4 o4 = inv * glm::dvec4(u, v, 0.0, 1.0), f4 = inv * glm::dvec4(u, v, 1.0, 1.0);
  glm::dvec3 o = glm::dvec3(o4) / o4.w, dir = glm::dvec3(f4) / f4.w - o;
  RayCast best;
  for (size_t t = 0; t < tris.size(); t += 3) {
    glm::dvec3 a = tris[t], e1 = tris[t + 1] - a, e2 = tris[t + 2] - a;
    glm::dvec3 pv = glm::cross(dir, e2), tv = o - a, qv = glm::cross(tv, e1);
    double det = glm::dot(e1, pv);
    if (det == 0.0) continue;
    double bu = glm::dot(tv, pv) / det, bv = glm::dot(dir, qv) / det;
    if (bu < 0 || bv < 0 || bu + bv > 1) continue;
    glm::dvec4 h = m * glm::dvec4(o + glm::dot(e2, qv) / det * dir, 1.0);
    double z = h.z / h.w;
    if (h.w <= 0 || z < 0 || z > 1 || z >= best.depth) continue;
    best = {z, int(t / 3)};
  }
  return best;
}

// Triangles that cross the near plane and w = 0 (behind the eye), through a perspective map.
TEST(Raster, HomogeneousClippingMatchesRayCasting) {
  const uint32_t n = 128;
  glm::dmat4 view = glm::lookAt(glm::dvec3(0, 0, 0), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0));
  glm::dmat4 proj = glm::perspective(glm::radians(70.0), 1.0, 0.5, 50.0);
  glm::dmat4 gl_to_tex(0.5, 0, 0, 0, 0, -0.5, 0, 0, 0, 0, 0.5, 0, 0.5, 0.5, 0.5, 1);
  glm::dmat4 m = gl_to_tex * proj * view;
  std::vector<glm::dvec3> tris = {
      // A floor running from behind the eye to far away: crosses w = 0 and the near plane.
      {-30, -1, 20},
      {30, -1, 20},
      {0, -1, -45},
      // A wall slanting through the near plane.
      {-2, -3, 0.3},
      {3, 3, -4},
      {-1, 4, 0.2},
      // Entirely behind the eye: must not appear.
      {-1, -1, 2},
      {1, -1, 2},
      {0, 1, 3},
      // Beyond far: must not appear.
      {-50, -50, -60},
      {50, -50, -60},
      {0, 50, -60}};
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  for (size_t i = 0; i < tris.size(); ++i) {
    pos.insert(pos.end(), {float(tris[i].x), float(tris[i].y), float(tris[i].z)});
    idx.push_back(uint32_t(i));
  }
  Raster r = rasterize(one_mesh(pos, idx), glm::mat4(m), n, n);
  size_t agree = 0, compared = 0, covered = 0;
  double worst = 0.0;
  for (uint32_t p = 0; p < n * n; ++p) {
    double u = (p % n + 0.5) / n, v = (p / n + 0.5) / n;
    RayCast ref = ray_cast(tris, m, u, v);
    bool got = r.ids[p] != 0xffffffffu;
    covered += got;
    // Within 1/100 pixel of an edge either answer is right: skip where a nudge changes it.
    const double e = 0.01 / n;
    bool on_edge = false;
    for (glm::dvec2 d : {glm::dvec2(e, 0), glm::dvec2(-e, 0), glm::dvec2(0, e), glm::dvec2(0, -e)})
      on_edge |= ray_cast(tris, m, u + d.x, v + d.y).triangle != ref.triangle;
    if (on_edge) continue;
    ++compared;
    if (got != (ref.triangle >= 0) || (got && int(r.ids[p]) != ref.triangle)) continue;
    ++agree;
    if (got) worst = std::max(worst, std::abs(ref.depth - r.depth[p]));
  }
  EXPECT_GT(covered, n * n / 4);
  EXPECT_EQ(agree, compared);
  EXPECT_LT(worst, 1e-5);
  for (uint32_t id : r.ids) EXPECT_TRUE(id == 0xffffffffu || id < 2u) << "culled triangle drawn";
}

}  // namespace
}  // namespace shadow
