// The quality goals' probe: the boundary count (kernels/boundary.cl), over the view and per cell of
// the sample grid, against the double-precision count the bench calibrates with
// (oracle::boundary_share, boundary_cells), the share a goal reports against
// that count over the uniform 512 hard test of the same request, and the camera view's samples
// (view_samples) against the grid's pixels read on the host.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "engine/choose/quality_pick.hpp"
#include "engine/engine.hpp"
#include "engine/passes/boundary.hpp"
#include "engine/passes/view_samples.hpp"
#include "occluder_scene.hpp"
#include "oracle/metrics.hpp"

namespace shadow {
namespace {

// A synthetic camera view (eye at the origin looking down -z, 60 degrees vertical) of planes
// facing it, in five vertical bands: 0 at depth 10, normal +z; 1 the same plane, its normal turned
// 60 degrees about y (a crease); 2 at depth 40 with 1's normal (a silhouette); 3 the same plane,
// turned 15 degrees further, away from sun(); 4 at depth 40, normal +z, receiving no shadows.
// Pixels with NaN visibility see nothing.
struct SyntheticView {
  std::vector<float> position, normal;  // G-buffer layouts: 3 and 4 floats per pixel
  oracle::ViewSurface surface;          // the same, in double
  Camera camera;
  GBuffer upload(const cl::Runtime& runtime) const {
    GBuffer g;
    g.position = runtime.upload(position);
    g.normal = runtime.upload(normal);
    return g;
  }
};

// Lights bands 0, 1, 2 and 4, not 3.
Light sun() {
  Light l;
  l.direction = {-0.4f, 0.0f, -1.0f};
  return l;
}

SyntheticView synthetic_view(uint32_t w, uint32_t h, const std::vector<float>& visibility,
                             const Light& light) {
  SyntheticView v;
  v.camera.eye = {0, 0, 0};
  v.camera.target = {0, 0, -1};
  v.camera.fov_deg = 60;
  v.camera.width = w;
  v.camera.height = h;
  const double t = std::tan(glm::radians(30.0)), aspect = double(w) / h;
  const auto turned = [](double deg) {
    return glm::dvec3(-std::sin(glm::radians(deg)), 0, std::cos(glm::radians(deg)));
  };
  v.surface.eye = glm::dvec3(0.0);
  v.surface.pixel = 2 * t / h;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t band = 5 * size_t{x} / w;
      const double depth = band < 2 ? 10 : 40;
      const glm::dvec3 ray((2 * (x + 0.5) / w - 1) * t * aspect, (1 - 2 * (y + 0.5) / h) * t, -1);
      const bool seen = !std::isnan(visibility[size_t{y} * w + x]);
      const glm::vec3 p = seen ? glm::vec3(ray * depth) : glm::vec3(NAN);
      const glm::dvec3 n = band == 1 || band == 2 ? turned(60) : band == 3 ? turned(75) : turned(0);
      const glm::vec3 nf = glm::normalize(glm::vec3(n));
      const float receives = band == 4 ? 0.0f : 1.0f;
      v.position.insert(v.position.end(), {p.x, p.y, p.z});
      v.normal.insert(v.normal.end(), {nf.x, nf.y, nf.z, receives});
      v.surface.position.push_back(glm::dvec3(p));
      v.surface.normal.push_back(glm::dvec3(nf));
    }
  // Lit as the oracle lights the bench's views, from the float G-buffer the kernel reads.
  oracle::CameraHits hits;
  hits.width = w;
  hits.height = h;
  hits.position = v.surface.position;
  hits.normal = v.surface.normal;
  Scene scene;
  scene.instances = {Instance{}, Instance{}};
  scene.instances[1].receives_shadows = false;
  for (size_t i = 0; i < hits.position.size(); ++i) {
    const bool seen = !std::isnan(hits.position[i].x);
    hits.instance.push_back(!seen ? -1 : v.normal[4 * i + 3] != 0 ? 0 : 1);
  }
  v.surface.lit = oracle::view_surface(hits, scene, v.camera, light).lit;
  return v;
}

TEST(Boundary, KernelCountsAsTheOracleDoes) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  BoundaryPass pass(runtime, kernels);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const Light sun = shadow::sun();
  Light spot;  // its cone's rim crosses the view
  spot.type = LightType::kSpot;
  spot.position = {0, 0, 5};
  spot.direction = {0.1f, 0.05f, -1.0f};
  spot.cone_angle_deg = 30;
  // One pixel, a row, a column, views smaller than the grid, ragged sizes and 1080p; blobs of 0
  // and 1, soft values, and pixels the camera does not see (NaN), whose neighbours must not count
  // them.
  for (const Light& light : {sun, spot})
    for (auto [w, h] :
         {std::pair{1u, 1u}, {17u, 1u}, {1u, 23u}, {25u, 15u}, {333u, 77u}, {1920u, 1080u}}) {
      std::vector<float> v(size_t{w} * h);
      for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
          const float r = u(rng);
          const bool blob = std::sin(0.11f * float(x)) * std::cos(0.07f * float(y)) > 0.2f;
          v[size_t{y} * w + x] = r < 0.1f ? NAN : r < 0.15f ? 0.3f : blob ? 0.0f : 1.0f;
        }
      const SyntheticView view = synthetic_view(w, h, v, light);
      const GBuffer g = view.upload(runtime);
      Timeline t;
      const BoundaryCount got = pass.run(runtime.upload(v), g, view.camera, light, t);
      const double want = oracle::boundary_share(v, w, h, view.surface);
      const std::vector<oracle::CellBoundary> cells =
          oracle::boundary_cells(v, w, h, kSampleColumns, kSampleRows, view.surface);
      std::printf("[ boundary ] %s %ux%u: share %.6f (oracle %.6f), %.3f ms device\n",
                  light.type == LightType::kSpot ? "spot" : "sun", w, h, got.share, want,
                  t.timings().at(0).device_ms);
      EXPECT_EQ(got.share, want);  // the same counts: 0, 0.3 and 1 differ exactly
      ASSERT_EQ(got.cells.size(), cells.size());
      size_t boundary = 0;
      for (size_t i = 0; i < cells.size(); ++i) {
        EXPECT_EQ(got.cells[i], cells[i].boundary) << w << "x" << h << " cell " << i;
        boundary += cells[i].boundary;
      }
      const oracle::CellBoundary whole = oracle::boundary_cells(v, w, h, 1, 1, view.surface)[0];
      size_t seen = 0;  // the cells tile the view: their counts sum to the whole's
      for (const oracle::CellBoundary& c : cells) seen += c.seen;
      EXPECT_EQ(seen, whole.seen);
      EXPECT_EQ(boundary, whole.boundary);
      if (w == 1920) {
        EXPECT_GT(whole.boundary, 1000u);  // the edges are there to count
      }
    }
  Timeline t;
  const std::vector<float> unseen(64, NAN);
  const SyntheticView view = synthetic_view(8, 8, unseen, sun);
  const GBuffer g = view.upload(runtime);
  const BoundaryCount none = pass.run(runtime.upload(unseen), g, view.camera, sun, t);
  EXPECT_EQ(none.share, 0.0);
  for (uint32_t c : none.cells) EXPECT_EQ(c, 0u);
}

// By hand, on 100 rows of ten pixels (pixels small enough to tell a surface from a jump), each
// row the same (two columns per band of synthetic_view):
// the lit/dark changes between pixels on one lit plane count, those the geometry makes do not.
TEST(Boundary, EdgesTheGeometryMakesDoNotCount) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  BoundaryPass pass(runtime, kernels);
  const Light sun = shadow::sun();
  // The boundary pixels of each row.
  const auto count = [&](const std::vector<float>& row) {
    std::vector<float> v;
    for (int r = 0; r < 100; ++r) v.insert(v.end(), row.begin(), row.end());
    const SyntheticView view = synthetic_view(10, 100, v, sun);
    const GBuffer g = view.upload(runtime);
    Timeline t;
    const BoundaryCount got = pass.run(runtime.upload(v), g, view.camera, sun, t);
    const oracle::CellBoundary whole = oracle::boundary_cells(v, 10, 100, 1, 1, view.surface)[0];
    EXPECT_EQ(got.share, double(whole.boundary) / double(whole.seen));
    EXPECT_EQ(whole.boundary % 100, 0u);
    return whole.boundary / 100;
  };
  EXPECT_EQ(count({1, 0, 1, 1, 1, 1, 1, 1, 1, 1}), 2u);  // one lit plane: both sides count
  EXPECT_EQ(count({1, 1, 1, 1, 0, 1, 1, 1, 1, 1}), 2u);  // the same on band 2 (not with band 1)
  EXPECT_EQ(count({0, 0, 1, 1, 1, 1, 1, 1, 1, 1}), 0u);  // a crease
  EXPECT_EQ(count({0, 0, 0, 0, 1, 1, 1, 1, 1, 1}), 0u);  // a silhouette
  EXPECT_EQ(count({1, 1, 1, 1, 1, 1, 0, 0, 0, 0}), 0u);  // the dark side faces away from the light
  EXPECT_EQ(count({1, 1, 1, 1, 1, 1, 1, 1, 1, 0}), 0u);  // no shadows received there
}

TEST(Boundary, ViewSamplesAreTheGridsSeenPixels) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  ViewSamplesPass pass(runtime, kernels);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  // Views smaller than the grid (several samples on one pixel), ragged, and 1080p; pixels unseen
  // (NaN), receiving (w 1, 2) or not (w 0).
  for (auto [w, h] : {std::pair{1u, 1u}, {17u, 1u}, {1u, 23u}, {333u, 77u}, {1920u, 1080u}}) {
    std::vector<float> position(size_t{w} * h * 3), normal(size_t{w} * h * 4);
    for (size_t p = 0; p < size_t{w} * h; ++p) {
      const bool seen = u(rng) > -0.6f;
      for (int k = 0; k < 3; ++k) position[3 * p + k] = seen ? 100 * u(rng) : NAN;
      for (int k = 0; k < 3; ++k) normal[4 * p + k] = u(rng);
      normal[4 * p + 3] = float(int(1.5f * (u(rng) + 1)));  // 0, 1 or 2
    }
    GBuffer view;
    view.position = runtime.upload(position);
    view.normal = runtime.upload(normal);
    Timeline t;
    std::vector<uint32_t> cells;
    const std::vector<Sample> got = pass.run(view, w, h, t, &cells);
    std::vector<Sample> want;
    std::vector<uint32_t> want_cells;
    for (uint32_t r = 0; r < kSampleRows; ++r)
      for (uint32_t c = 0; c < kSampleColumns; ++c) {
        const size_t x = (2 * c + 1) * size_t{w} / (2 * kSampleColumns),
                     y = (2 * r + 1) * size_t{h} / (2 * kSampleRows), p = y * w + x;
        if (std::isnan(position[3 * p])) continue;
        want_cells.push_back(r * kSampleColumns + c);
        const bool receives = normal[4 * p + 3] != 0;
        want.push_back({{position[3 * p], position[3 * p + 1], position[3 * p + 2]},
                        receives ? glm::dvec3(normal[4 * p], normal[4 * p + 1], normal[4 * p + 2])
                                 : glm::dvec3(0.0)});
      }
    ASSERT_EQ(got.size(), want.size()) << w << "x" << h;
    EXPECT_EQ(cells, want_cells) << w << "x" << h;
    for (size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(got[i].p, want[i].p) << w << "x" << h << " sample " << i;
      EXPECT_EQ(got[i].n, want[i].n) << w << "x" << h << " sample " << i;
    }
  }
}

// A goal's reported share is that of the hard test against a uniform 512 map of the request.
TEST(Boundary, AGoalReportsTheProbesShare) {
  RenderRequest r = testing::occluder_request();
  r.camera.width = 160;
  r.camera.height = 120;
  r.products = {Product::kVisibility};
  r.quality = {Quality::Goal::kMaxError, 0.01};
  const RenderResult goal = testing::engine().render(r);
  ASSERT_TRUE(goal.quality.has_value());
  ASSERT_EQ(goal.quality->boundary_share.size(), 1u);
  bool probed = false;
  for (const PassTiming& p : goal.timings) probed |= p.pass == "quality_probe.boundary.count";
  EXPECT_TRUE(probed);

  RenderRequest probe = r;
  probe.quality = {};
  probe.shadow_map.technique = Technique::kUniform;
  probe.shadow_map.size = kQualityProbeSize;
  probe.products = {Product::kVisibility, Product::kPosition};
  const RenderResult hard = testing::engine().render(probe);
  // The oracle's share over the view the render saw: every seen point on a quad facing up, under
  // the sun straight down.
  oracle::ViewSurface surface;
  surface.eye = glm::dvec3(r.camera.eye);
  surface.pixel = 2 * std::tan(glm::radians(0.5 * double(r.camera.fov_deg))) / 120;
  const auto texture = [&](Product kind) -> const std::vector<float>& {
    for (const Texture& t : hard.textures)
      if (t.kind == kind) return t.data;
    throw std::logic_error("no such texture");
  };
  const std::vector<float>& at = texture(Product::kPosition);
  for (size_t i = 0; i < 160 * 120; ++i) {
    surface.position.emplace_back(at[3 * i], at[3 * i + 1], at[3 * i + 2]);
    surface.normal.emplace_back(0, 1, 0);
    surface.lit.push_back(!std::isnan(at[3 * i]));
  }
  const double want = oracle::boundary_share(texture(Product::kVisibility), 160, 120, surface);
  std::printf("[ boundary ] occluder scene: probe share %.5f, uniform 512 render %.5f\n",
              goal.quality->boundary_share[0], want);
  EXPECT_GT(want, 0.0);  // the occluder's shadow is in view
  EXPECT_EQ(goal.quality->boundary_share[0], want);
}

}  // namespace
}  // namespace shadow
