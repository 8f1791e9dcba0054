// The rasterizer kernels against exact CPU references: coverage and the fill rule, depth
// interpolation, and homogeneous clipping (a double-precision ray cast per pixel).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/passes/rasterizer.hpp"
#include "engine_fixture.hpp"

namespace shadow {
namespace {

// One device per kernel shape (issue 42): every test runs the CPU shape's kernels (rasterizer.cl)
// and the GPU shape's (its _gpu kernels, work-groups and local memory, which PoCL runs too).
struct Device : testing::ProfileDevice {
  using ProfileDevice::ProfileDevice;
  Rasterizer rasterizer{runtime, kernels};
};

Device& device(const std::string& shape) {
  static Device cpu("cpu"), gpu("gpu");
  return shape == "gpu" ? gpu : cpu;
}

class Raster : public ::testing::TestWithParam<std::string> {
 protected:
  Device& dev() { return device(GetParam()); }
};

struct Image {
  std::vector<float> depth;
  std::vector<uint32_t> ids;
};

// Rasterizes every triangle of `scene` (one instance per mesh) through `world_to_ndc`; without
// ids, `ids` stays empty.
Image rasterize(Device& d, const Scene& scene, const glm::mat4& world_to_ndc, uint32_t w,
                uint32_t h, const RasterPaths& paths = RasterPaths{}, bool write_ids = true) {
  Timeline timeline;
  SceneBuffers buffers(d.runtime, d.kernels, scene, timeline);
  auto draws = make_draws(scene, buffers, world_to_ndc, [](const Instance&) { return true; });
  d.rasterizer.set_paths(paths);
  const RasterOutput& out =
      d.rasterizer.run(buffers, draws, w, h, write_ids, "test", "test", timeline);
  d.rasterizer.set_paths(RasterPaths{});
  Image r{std::vector<float>(size_t{w} * h), {}};
  d.runtime.read(out.depth, r.depth.data(), r.depth.size() * sizeof(float));
  if (write_ids) {
    r.ids.resize(size_t{w} * h);
    d.runtime.read(out.ids, r.ids.data(), r.ids.size() * sizeof(uint32_t));
  }
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
TEST_P(Raster, SharedEdgesAreNeitherDoubleCoveredNorHoled) {
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
    Image r = rasterize(dev(), s, pixel_space(n, n), n, n);
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
TEST_P(Raster, TopLeftRuleOnATriangle) {
  const uint32_t n = 16;
  // Right triangle with a top edge (y = 2.5) and a left edge (x = 2.5) through pixel centres.
  for (bool flip : {false, true}) {
    std::vector<uint32_t> idx =
        flip ? std::vector<uint32_t>{0, 2, 1} : std::vector<uint32_t>{0, 1, 2};
    Scene s = one_mesh({2.5f, 2.5f, 0.5f, 10.5f, 2.5f, 0.5f, 2.5f, 10.5f, 0.5f}, idx);
    Image r = rasterize(dev(), s, pixel_space(n, n), n, n);
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x) {
        int dx = int(x) - 2, dy = int(y) - 2;  // pixel centre offset from the right-angle vertex
        bool inside = dx >= 0 && dy >= 0 && dx + dy < 8;  // hypotenuse is a bottom-right edge
        EXPECT_EQ(r.ids[y * n + x] != 0xffffffffu, inside) << x << "," << y << " flip " << flip;
      }
  }
}

// Depth at every covered pixel centre equals the triangle's plane evaluated in double.
TEST_P(Raster, DepthInterpolationMatchesThePlane) {
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
  Image r = rasterize(dev(), s, pixel_space(n, n), n, n);
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

// A perspective map's matrix (the eye at the origin looking down -z, near 0.5, far 50) and the
// raster of `tris` through it against the double-precision ray cast, pixels within 1/100 pixel of
// an edge (where either answer is right) left out.
glm::dmat4 perspective_map() {
  glm::dmat4 view = glm::lookAt(glm::dvec3(0, 0, 0), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0));
  glm::dmat4 proj = glm::perspective(glm::radians(70.0), 1.0, 0.5, 50.0);
  glm::dmat4 gl_to_tex(0.5, 0, 0, 0, 0, -0.5, 0, 0, 0, 0, 0.5, 0, 0.5, 0.5, 0.5, 1);
  return gl_to_tex * proj * view;
}
struct Agreement {
  size_t agree = 0, compared = 0, covered = 0;
  double worst = 0.0;  // depth
  Image image;
};
Agreement against_ray_casting(Device& d, const std::vector<glm::dvec3>& tris, const glm::dmat4& m,
                              uint32_t n) {
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  for (size_t i = 0; i < tris.size(); ++i) {
    pos.insert(pos.end(), {float(tris[i].x), float(tris[i].y), float(tris[i].z)});
    idx.push_back(uint32_t(i));
  }
  Agreement a;
  a.image = rasterize(d, one_mesh(pos, idx), glm::mat4(m), n, n);
  const Image& r = a.image;
  for (uint32_t p = 0; p < n * n; ++p) {
    double u = (p % n + 0.5) / n, v = (p / n + 0.5) / n;
    RayCast ref = ray_cast(tris, m, u, v);
    bool got = r.ids[p] != 0xffffffffu;
    a.covered += got;
    const double e = 0.01 / n;
    bool on_edge = false;
    for (glm::dvec2 d : {glm::dvec2(e, 0), glm::dvec2(-e, 0), glm::dvec2(0, e), glm::dvec2(0, -e)})
      on_edge |= ray_cast(tris, m, u + d.x, v + d.y).triangle != ref.triangle;
    if (on_edge) continue;
    ++a.compared;
    if (got != (ref.triangle >= 0) || (got && int(r.ids[p]) != ref.triangle)) continue;
    ++a.agree;
    if (got) a.worst = std::max(a.worst, std::abs(ref.depth - r.depth[p]));
  }
  return a;
}

// Triangles that cross the near plane and w = 0 (behind the eye), through a perspective map.
TEST_P(Raster, HomogeneousClippingMatchesRayCasting) {
  const uint32_t n = 128;
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
  const Agreement a = against_ray_casting(dev(), tris, perspective_map(), n);
  EXPECT_GT(a.covered, n * n / 4);
  EXPECT_EQ(a.agree, a.compared);
  EXPECT_LT(a.worst, 1e-5);
  for (uint32_t id : a.image.ids)
    EXPECT_TRUE(id == 0xffffffffu || id < 2u) << "culled triangle drawn";
}

// Set-up makes room for the input triangles and a few more (1/16 and 1024) for the fans that
// clipping adds, and does not wait for their count: binning reads it with its totals, and a map
// whose clipped fans did not fit is set up again with room for them. 35 x 35 slivers, each in a
// cell of the view of its own, each with one corner before the near plane and two past it, so
// that clipping makes it a quad, two records: 1225 fan triangles past that room, every one
// drawn, and counted by the load. (The ray cast tests each pixel's cell and its neighbours: no
// other sliver reaches it.)
TEST_P(Raster, ClippedFansPastTheFirstRoomAreAllDrawn) {
  const uint32_t n = 256, cells = 35, count = cells * cells;
  static_assert(count > count / 16 + 1024);
  const double span = 0.6, cell = 2 * span / cells, side = 0.8 * cell;  // view directions x / -z
  std::vector<glm::dvec3> tris;
  for (uint32_t j = 0; j < cells; ++j)
    for (uint32_t i = 0; i < cells; ++i) {
      const double cx = -span + (i + 0.1) * cell, cy = -span + (j + 0.1) * cell;
      tris.push_back({cx * 2, cy * 2, -2});                                // past the near plane
      tris.push_back({(cx + side) * 2.5, cy * 2.5, -2.5});                 // past it
      tris.push_back({(cx + 0.5 * side) * 0.3, (cy + side) * 0.3, -0.3});  // before it
    }
  const glm::dmat4 m = perspective_map(), inverse = glm::inverse(m);
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  for (size_t k = 0; k < tris.size(); ++k) {
    pos.insert(pos.end(), {float(tris[k].x), float(tris[k].y), float(tris[k].z)});
    idx.push_back(uint32_t(k));
  }
  // The load (Rasterizer::load, which sets up on its own) counts every record binning does.
  Device& d = dev();
  Timeline timeline;
  const Scene scene = one_mesh(pos, idx);
  SceneBuffers buffers(d.runtime, d.kernels, scene, timeline);
  const auto draws = make_draws(scene, buffers, glm::mat4(m), [](const Instance&) { return true; });
  const std::vector<RasterLoad> load = d.rasterizer.load(buffers, draws, n, 1, "load", timeline);
  const RasterOutput& out = d.rasterizer.run(buffers, draws, n, n, true, "test", "test", timeline);
  EXPECT_EQ(out.load, load.at(0));
  std::vector<uint32_t> ids(size_t{n} * n);
  d.runtime.read(out.ids, ids.data(), ids.size() * sizeof(uint32_t));
  // The slivers of the cell that texture point (u, v) looks along, and of its neighbours.
  const auto near_slivers = [&](double u, double v) {
    const glm::dvec4 h = inverse * glm::dvec4(u, v, 1.0, 1.0);
    const glm::dvec3 d = glm::dvec3(h) / h.w;
    const int i = int(std::floor((d.x / -d.z + span) / cell)),
              j = int(std::floor((d.y / -d.z + span) / cell));
    std::vector<glm::dvec3> near;
    std::vector<int> id;
    for (int y = j - 1; y <= j + 1; ++y)
      for (int x = i - 1; x <= i + 1; ++x)
        if (x >= 0 && y >= 0 && x < int(cells) && y < int(cells)) {
          const size_t t = size_t(y) * cells + x;
          near.insert(near.end(), tris.begin() + 3 * t, tris.begin() + 3 * t + 3);
          id.push_back(int(t));
        }
    return std::pair{near, id};
  };
  size_t agree = 0, compared = 0, covered = 0;
  for (uint32_t p = 0; p < n * n; ++p) {
    const double u = (p % n + 0.5) / n, v = (p / n + 0.5) / n, e = 0.01 / n;
    const auto [near, id] = near_slivers(u, v);
    const RayCast ref = ray_cast(near, m, u, v);
    bool on_edge = false;
    for (glm::dvec2 d : {glm::dvec2(e, 0), glm::dvec2(-e, 0), glm::dvec2(0, e), glm::dvec2(0, -e)})
      on_edge |= ray_cast(near, m, u + d.x, v + d.y).triangle != ref.triangle;
    covered += ids[p] != 0xffffffffu;
    if (on_edge) continue;
    ++compared;
    const int want = ref.triangle < 0 ? -1 : id[ref.triangle];
    agree += (ids[p] == 0xffffffffu ? -1 : int(ids[p])) == want;
  }
  std::printf("[ raster   ] %zu of %u pixels covered by %u clipped slivers\n", covered, n * n,
              count);
  EXPECT_GT(covered, n * n / 8);
  EXPECT_GT(compared, n * n / 2);
  EXPECT_EQ(agree, compared);
}

// The CPU reference for maps through pixel_space(w, h): vertices snapped to 1/256 pixel as the
// kernel does (in float), coverage by exact 64-bit edge functions with the top-left rule, depth
// by the double-precision plane through the snapped vertices, clamped to 0..1.
struct Reference {
  std::vector<double> depth;      // nearest, 1 where empty
  std::vector<double> runner_up;  // second nearest depth of another triangle
  std::vector<int> id;            // nearest triangle, -1 where empty (ties: the lower id)
};

Reference reference(const std::vector<float>& pos, const std::vector<uint32_t>& idx, uint32_t w,
                    uint32_t h) {
  Reference ref{std::vector<double>(size_t{w} * h, 1.0), std::vector<double>(size_t{w} * h, 1.0),
                std::vector<int>(size_t{w} * h, -1)};
  auto snap = [](float v, uint32_t n) {
    return int64_t(std::nearbyint((v * (1.0f / float(n))) * float(n) * 256.0f));
  };
  for (size_t t = 0; t < idx.size() / 3; ++t) {
    int64_t x[3], y[3];
    double z[3];
    for (int k = 0; k < 3; ++k) {
      const float* v = &pos[3 * idx[3 * t + k]];
      x[k] = snap(v[0], w), y[k] = snap(v[1], h), z[k] = v[2];
    }
    int64_t area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    if (area == 0) continue;
    if (area < 0) std::swap(x[1], x[2]), std::swap(y[1], y[2]), std::swap(z[1], z[2]);
    // Inside: every edge function > 0, or == 0 on a top edge (horizontal, running right) or a
    // left edge (running up in the y-down image).
    auto inside = [&](int64_t px, int64_t py) {
      for (int k = 0; k < 3; ++k) {
        int64_t ax = x[k], ay = y[k], bx = x[(k + 1) % 3], by = y[(k + 1) % 3];
        int64_t e = (bx - ax) * (py - ay) - (by - ay) * (px - ax);
        bool top_left = (by - ay) < 0 || ((by - ay) == 0 && (bx - ax) > 0);
        if (e < 0 || (e == 0 && !top_left)) return false;
      }
      return true;
    };
    const glm::dvec3 a(x[0] / 256.0, y[0] / 256.0, z[0]), b(x[1] / 256.0, y[1] / 256.0, z[1]),
        c(x[2] / 256.0, y[2] / 256.0, z[2]);
    const glm::dvec3 nrm = glm::cross(b - a, c - a);
    for (uint32_t py = 0; py < h; ++py)
      for (uint32_t px = 0; px < w; ++px) {
        if (!inside(int64_t(px) * 256 + 128, int64_t(py) * 256 + 128)) continue;
        double d = a.z - (nrm.x * (px + 0.5 - a.x) + nrm.y * (py + 0.5 - a.y)) / nrm.z;
        d = std::clamp(d, 0.0, 1.0);
        size_t p = size_t{py} * w + px;
        if (ref.id[p] < 0 || d < ref.depth[p]) {
          ref.runner_up[p] = ref.depth[p];
          ref.depth[p] = d, ref.id[p] = int(t);
        } else if (d != ref.depth[p]) {  // an exact tie (a copy of a triangle) is no doubt
          ref.runner_up[p] = std::min(ref.runner_up[p], d);
        }
      }
  }
  return ref;
}

// A scene for every kernel path: a tilted quad over the whole map first (full tiles; it sets
// the tiles' far bound), then tiny triangles under a pixel across (point path), medium ones
// (32-bit edges), large ones (64-bit edges, full tiles of their own), many of each behind the
// quad (the hierarchical cull) or just in front of it, and last the quad again (equal depths:
// the lower id wins).
void paths_scene(uint32_t w, uint32_t h, std::vector<float>& pos, std::vector<uint32_t>& idx) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto tri = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const auto base = uint32_t(pos.size() / 3);
    pos.insert(pos.end(), {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z});
    idx.insert(idx.end(), {base, base + 1, base + 2});
  };
  const float W = float(w), H = float(h);
  auto quad_z = [&](float x, float y) { return 0.6f + 0.002f * x / W + 0.003f * y / H; };
  auto quad = [&] {
    const glm::vec3 p0(-3, -2, quad_z(-3, -2)), p1(W + 2, -3, quad_z(W + 2, -3)),
        p2(W + 3, H + 2, quad_z(W + 3, H + 2)), p3(-2, H + 3, quad_z(-2, H + 3));
    tri(p0, p1, p2);
    tri(p0, p2, p3);
  };
  quad();
  // Decals 1e-4 in front of the quad: a cull without its rounding margin would drop them.
  for (int i = 0; i < 150; ++i) {
    const glm::vec2 c(u(rng) * W, u(rng) * H);
    const float size = 0.5f + 20.0f * u(rng);
    glm::vec3 v[3];
    for (int k = 0; k < 3; ++k) {
      const glm::vec2 p = c + size * glm::vec2(u(rng) - 0.5f, u(rng) - 0.5f);
      v[k] = glm::vec3(p, quad_z(p.x, p.y) - 1e-4f);
    }
    tri(v[0], v[1], v[2]);
  }
  auto scatter = [&](int count, float lo, float hi) {
    for (int i = 0; i < count; ++i) {
      const glm::vec3 centre(u(rng) * W, u(rng) * H, 0.2f + 0.75f * u(rng));
      const float size = lo + (hi - lo) * u(rng);
      glm::vec3 v[3];
      for (int k = 0; k < 3; ++k)
        v[k] = centre +
               glm::vec3(size * (u(rng) - 0.5f), size * (u(rng) - 0.5f), 0.1f * (u(rng) - 0.5f));
      tri(v[0], v[1], v[2]);
    }
  };
  scatter(600, 0.2f, 1.2f);     // point path (and some boxes of two pixels)
  scatter(200, 2.0f, 40.0f);    // 32-bit edges
  scatter(12, 100.0f, 400.0f);  // 64-bit edges, full tiles
  quad();
}

// Every path against the CPU reference, on a map with partial tiles at its right and bottom.
TEST_P(Raster, EveryPathMatchesTheReference) {
  const uint32_t w = 288, h = 160;  // 4.5 x 2.5 tiles
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  paths_scene(w, h, pos, idx);
  const uint32_t tris = uint32_t(idx.size() / 3);
  const Reference ref = reference(pos, idx, w, h);
  RasterPaths every;
  every.hiz = true;
  Image r = rasterize(dev(), one_mesh(pos, idx), pixel_space(w, h), w, h, every);
  size_t ids_checked = 0, front = 0;
  double worst = 0.0;
  for (size_t p = 0; p < r.depth.size(); ++p) {
    ASSERT_EQ(r.ids[p] != 0xffffffffu, ref.id[p] >= 0) << "coverage at " << p % w << "," << p / w;
    worst = std::max(worst, std::abs(double(r.depth[p]) - ref.depth[p]));
    EXPECT_NE(r.ids[p], tris - 1) << "the second quad won a tie at " << p;
    EXPECT_NE(r.ids[p], tris - 2) << "the second quad won a tie at " << p;
    if (ref.runner_up[p] - ref.depth[p] < 1e-5) continue;  // too close to call in float
    ASSERT_EQ(int(r.ids[p]), ref.id[p]) << "nearest at " << p % w << "," << p / w;
    ++ids_checked;
    front += r.ids[p] > 1;
  }
  EXPECT_GT(ids_checked, r.depth.size() * 9 / 10);
  EXPECT_GT(front, r.depth.size() / 10);  // the small and large triangles in front of the quad
  EXPECT_LT(worst, 2e-6) << "worst depth error";
}

// The paths only change speed: all of them off, or the default set, gives the same bits as all
// of them on, with and without ids.
// (Every program variant is a PoCL compile, so the single-path variants are left to the bench.)
TEST_P(Raster, PathsChangeNoBit) {
  const uint32_t w = 288, h = 160;
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  paths_scene(w, h, pos, idx);
  const Scene s = one_mesh(pos, idx);
  const glm::mat4 m = pixel_space(w, h);
  RasterPaths every;
  every.hiz = true;
  const Image all = rasterize(dev(), s, m, w, h, every);
  const RasterPaths none{false, false, false, false, false, false};  // every field
  const Image plain = rasterize(dev(), s, m, w, h, none);
  EXPECT_EQ(plain.depth, all.depth);
  EXPECT_EQ(plain.ids, all.ids);
  EXPECT_EQ(rasterize(dev(), s, m, w, h, RasterPaths{}).ids, all.ids);  // the default paths
  EXPECT_EQ(rasterize(dev(), s, m, w, h, every, false).depth, all.depth);
  EXPECT_EQ(rasterize(dev(), s, m, w, h, none, false).depth, all.depth);
}

// The two shapes write the same bits (depth and ids), the GPU shape's lists being in atomic order:
// on the paths scene, with and without the per-tile (CPU) and per-block (GPU) hierarchical z, and
// on a crowd of 4000 small triangles and 40 large ones over 3 x 2 tiles, every tile's records
// more than a work-group stages at once.
TEST(RasterShapes, TheGpuShapeWritesTheCpuShapesBits) {
  const auto same = [](const Scene& s, const glm::mat4& m, uint32_t w, uint32_t h,
                       const RasterPaths& paths, const char* what) {
    for (bool ids : {true, false}) {
      const Image cpu = rasterize(device("cpu"), s, m, w, h, paths, ids);
      const Image gpu = rasterize(device("gpu"), s, m, w, h, paths, ids);
      EXPECT_EQ(0, std::memcmp(cpu.depth.data(), gpu.depth.data(), cpu.depth.size() * 4))
          << what << (ids ? ", ids" : "");
      EXPECT_EQ(cpu.ids, gpu.ids) << what;
    }
  };
  const uint32_t w = 288, h = 160;
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  paths_scene(w, h, pos, idx);
  RasterPaths hiz;
  hiz.hiz = true;
  same(one_mesh(pos, idx), pixel_space(w, h), w, h, RasterPaths{}, "paths scene");
  same(one_mesh(pos, idx), pixel_space(w, h), w, h, hiz, "paths scene, hierarchical z");

  const uint32_t cw = 3 * Rasterizer::kTile - 5, ch = 2 * Rasterizer::kTile;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  pos.clear(), idx.clear();
  for (int t = 0; t < 4040; ++t) {
    const float size = t < 4000 ? 0.3f + 4.0f * u(rng) : 40.0f + 200.0f * u(rng);
    const glm::vec2 c(u(rng) * cw, u(rng) * ch);
    const auto base = uint32_t(pos.size() / 3);
    // Flat triangles at 9 depths: many exact ties, which the lower id wins in either shape.
    const float z = std::round(u(rng) * 8.0f) / 8.0f * 0.9f + 0.05f;
    for (int k = 0; k < 3; ++k) {
      const glm::vec2 p = c + size * glm::vec2(u(rng) - 0.5f, u(rng) - 0.5f);
      pos.insert(pos.end(), {p.x, p.y, z});
    }
    idx.insert(idx.end(), {base, base + 1, base + 2});
  }
  same(one_mesh(pos, idx), pixel_space(cw, ch), cw, ch, RasterPaths{}, "crowd");
  same(one_mesh(pos, idx), pixel_space(cw, ch), cw, ch, hiz, "crowd, hierarchical z");
}

// The raster's load (raster_load) against a double-precision count: random triangles (some
// reaching past the viewport, some between pixel centres) and a quad over the whole viewport.
// A box holds the pixels whose centres lie within the snapped vertices' bounds; at level k the
// box's pixels shifted down k bits, its overlaps the 64^2 tiles it meets there. Level 0 is what
// Rasterizer::run's binning counts.
TEST_P(Raster, LoadCountsEachBoxsPixelsAndTiles) {
  const uint32_t n = 256, levels = Rasterizer::kMaxLoadLevels;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> at(-20.0f, n + 20.0f), span(0.1f, 90.0f), z(0.05f, 0.95f);
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  const auto tri = [&](glm::vec2 a, glm::vec2 b, glm::vec2 c) {
    const uint32_t v = uint32_t(pos.size() / 3);
    for (glm::vec2 p : {a, b, c}) pos.insert(pos.end(), {p.x, p.y, z(rng)});
    idx.insert(idx.end(), {v, v + 1, v + 2});
  };
  for (int t = 0; t < 400; ++t) {
    const glm::vec2 o(at(rng), at(rng));
    const float s = span(rng);
    tri(o, o + glm::vec2(s * 0.9f, s * 0.2f), o + glm::vec2(s * 0.3f, s));
  }
  tri({0, 0}, {float(n), 0}, {float(n), float(n)});
  tri({0, 0}, {float(n), float(n)}, {0, float(n)});

  std::vector<RasterLoad> expected(levels);
  for (size_t t = 0; t < idx.size() / 3; ++t) {
    // Snapped to 1/256 pixel, as the rasterizer sees them; pixel i's centre is at i + 0.5.
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 2; ++a) {
        const double v = std::nearbyint(pos[3 * idx[3 * t + k] + a] * 256.0) / 256.0;
        lo[a] = std::min(lo[a], v), hi[a] = std::max(hi[a], v);
      }
    int64_t first[2], last[2];
    for (int a = 0; a < 2; ++a) {
      first[a] = std::max<int64_t>(int64_t(std::ceil(lo[a] - 0.5)), 0);
      last[a] = std::min<int64_t>(int64_t(std::floor(hi[a] - 0.5)), n - 1);
    }
    if (first[0] > last[0] || first[1] > last[1]) continue;  // between pixel centres
    for (uint32_t k = 0; k < levels; ++k) {
      const int64_t x0 = first[0] >> k, x1 = last[0] >> k, y0 = first[1] >> k, y1 = last[1] >> k;
      expected[k].box_pixels += uint64_t((x1 - x0 + 1) * (y1 - y0 + 1));
      for (int64_t ty = 0; ty * Rasterizer::kTile < (n >> k); ++ty)
        for (int64_t tx = 0; tx * Rasterizer::kTile < (n >> k); ++tx) {
          const int64_t tile_lo_x = tx * Rasterizer::kTile, tile_lo_y = ty * Rasterizer::kTile;
          expected[k].overlaps += x0 < tile_lo_x + Rasterizer::kTile && x1 >= tile_lo_x &&
                                  y0 < tile_lo_y + Rasterizer::kTile && y1 >= tile_lo_y;
        }
    }
  }
  ASSERT_GE(expected[0].box_pixels, 2ull * n * n);  // the quad's two boxes
  Device& d = dev();
  Timeline timeline;
  const Scene s = one_mesh(pos, idx);
  SceneBuffers buffers(d.runtime, d.kernels, s, timeline);
  const auto draws =
      make_draws(s, buffers, pixel_space(n, n), [](const Instance&) { return true; });
  const std::vector<RasterLoad> load =
      d.rasterizer.load(buffers, draws, n, levels, "test_load", timeline);
  ASSERT_EQ(load.size(), levels);
  for (uint32_t k = 0; k < levels; ++k) {
    EXPECT_EQ(load[k].box_pixels, expected[k].box_pixels) << "level " << k;
    EXPECT_EQ(load[k].overlaps, expected[k].overlaps) << "level " << k;
  }
  // Binning counts the same at its own size.
  const RasterOutput& out = d.rasterizer.run(buffers, draws, n, n, false, "test", "test", timeline);
  EXPECT_EQ(out.load, load[0]);
  // The raster it enqueued after binning is never read. With a cold kernel cache PoCL compiles
  // it on a worker thread, which must not still run when exit destroys LLVM's statics (a
  // segfault after the test passed, on every fresh machine).
  d.runtime.finish();
}

INSTANTIATE_TEST_SUITE_P(Shapes, Raster, ::testing::Values("cpu", "gpu"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

}  // namespace
}  // namespace shadow
