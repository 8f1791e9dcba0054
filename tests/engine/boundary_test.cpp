// The quality goals' probe: the boundary count (kernels/reduce.cl), over the view and per cell of
// the sample grid, against the double-precision count the bench calibrates with
// (oracle::boundary_share, boundary_cells), the share a goal reports against
// that count over the uniform 512 hard test of the same request, and the camera view's samples
// (view_samples) against the grid's pixels read on the host.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "engine/engine.hpp"
#include "engine/passes/boundary.hpp"
#include "engine/passes/view_samples.hpp"
#include "engine/quality_pick.hpp"
#include "occluder_scene.hpp"
#include "oracle/metrics.hpp"

namespace shadow {
namespace {

TEST(Boundary, KernelCountsAsTheOracleDoes) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  BoundaryPass pass(runtime, kernels);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  // One pixel, a row, a column, views smaller than the grid, ragged sizes and 1080p; blobs of 0
  // and 1, soft values, and pixels the camera does not see (NaN), whose neighbours must not count
  // them.
  for (auto [w, h] :
       {std::pair{1u, 1u}, {17u, 1u}, {1u, 23u}, {25u, 15u}, {333u, 77u}, {1920u, 1080u}}) {
    std::vector<float> v(size_t{w} * h);
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        const float r = u(rng);
        const bool blob = std::sin(0.11f * float(x)) * std::cos(0.07f * float(y)) > 0.2f;
        v[size_t{y} * w + x] = r < 0.1f ? NAN : r < 0.15f ? 0.3f : blob ? 0.0f : 1.0f;
      }
    Timeline t;
    const BoundaryCount got = pass.run(runtime.upload(v), w, h, t);
    const double want = oracle::boundary_share(v, w, h);
    const std::vector<oracle::CellBoundary> cells =
        oracle::boundary_cells(v, w, h, kSampleColumns, kSampleRows);
    std::printf("[ boundary ] %ux%u: share %.6f (oracle %.6f), %.3f ms device\n", w, h, got.share,
                want, t.timings().at(0).device_ms);
    EXPECT_EQ(got.share, want);  // the same counts: 0, 0.3 and 1 differ exactly
    ASSERT_EQ(got.cells.size(), cells.size());
    size_t boundary = 0;
    for (size_t i = 0; i < cells.size(); ++i) {
      EXPECT_EQ(got.cells[i], cells[i].boundary) << w << "x" << h << " cell " << i;
      boundary += cells[i].boundary;
    }
    size_t seen = 0;  // the cells tile the view: their counts sum to the whole's
    for (const oracle::CellBoundary& c : cells) seen += c.seen;
    EXPECT_EQ(seen, oracle::boundary_cells(v, w, h, 1, 1)[0].seen);
    EXPECT_EQ(boundary, oracle::boundary_cells(v, w, h, 1, 1)[0].boundary);
  }
  Timeline t;
  const std::vector<float> unseen(64, NAN);
  const BoundaryCount none = pass.run(runtime.upload(unseen), 8, 8, t);
  EXPECT_EQ(none.share, 0.0);
  for (uint32_t c : none.cells) EXPECT_EQ(c, 0u);
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
  const RenderResult goal = testing::shared_engine().render(r);
  ASSERT_TRUE(goal.quality.has_value());
  ASSERT_EQ(goal.quality->boundary_share.size(), 1u);
  bool probed = false;
  for (const PassTiming& p : goal.timings) probed |= p.pass == "quality_probe.boundary.count";
  EXPECT_TRUE(probed);

  RenderRequest probe = r;
  probe.quality = {};
  probe.shadow_map.technique = Technique::kUniform;
  probe.shadow_map.size = kQualityProbeSize;
  const RenderResult hard = testing::shared_engine().render(probe);
  const double want = oracle::boundary_share(hard.textures.at(0).data, 160, 120);
  std::printf("[ boundary ] occluder scene: probe share %.5f, uniform 512 render %.5f\n",
              goal.quality->boundary_share[0], want);
  EXPECT_GT(want, 0.0);  // the occluder's shadow is in view
  EXPECT_EQ(goal.quality->boundary_share[0], want);
}

}  // namespace
}  // namespace shadow
