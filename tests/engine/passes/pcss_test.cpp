// PCSS against geometry: a straight occluder edge at height h over a ground plane, under a sun
// of angular diameter theta straight down. The ground's visibility across the edge is the
// fraction of the sun's disk not hidden: with s = x / (h tan(theta / 2)) in [-1, 1],
// f(s) = 1/2 + (s sqrt(1 - s^2) + asin s) / pi. PCSS's PCF over a disk of the estimated
// penumbra radius reproduces that profile, so its width grows linearly with h.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "engine/engine.hpp"
#include "engine_fixture.hpp"
#include "sun_edge_scene.hpp"

namespace shadow {
namespace {

using testing::disk_fraction;
using testing::engine;
using testing::sun_edge_request;

struct EdgeFit {
  double mae = 0;          // |PCSS - f(s)| over ground pixels within 1.5 penumbra half-widths
  double width_10_90 = 0;  // measured, world units
};

// The ground under the edge (sun_edge_scene.hpp), 480x320.
EdgeFit edge_fit(float h, float theta_deg) {
  const RenderRequest r = sun_edge_request(h, theta_deg, 480, 320);
  const RenderResult res = engine().render(r);
  const Texture& vis = res.textures[0];
  const Texture& pos = res.textures[1];
  const double half = h * std::tan(0.5 * theta_deg * M_PI / 180);
  // Bins along x for the 10-90 width; MAE against the closed form per pixel.
  const int bins = 40;
  std::vector<double> sum(bins), count(bins);
  double err = 0;
  size_t n = 0;
  for (size_t p = 0; p < size_t{vis.width} * vis.height; ++p) {
    const float x = pos.data[3 * p], y = pos.data[3 * p + 1], z = pos.data[3 * p + 2];
    if (std::isnan(x) || std::abs(y) > 1e-3f || std::abs(z) > 2.0f || std::abs(x) > 1.5 * half)
      continue;
    err += std::abs(vis.data[p] - disk_fraction(x / half));
    ++n;
    const int b = int((x / (1.5 * half) + 1) / 2 * bins);
    if (b >= 0 && b < bins) sum[b] += vis.data[p], count[b] += 1;
  }
  EdgeFit fit;
  fit.mae = err / std::max<size_t>(n, 1);
  double x10 = NAN, x90 = NAN;
  for (int b = 0; b < bins; ++b) {
    if (count[b] == 0) continue;
    const double x = ((b + 0.5) / bins * 2 - 1) * 1.5 * half, v = sum[b] / count[b];
    if (std::isnan(x10) && v >= 0.1) x10 = x;
    if (std::isnan(x90) && v >= 0.9) x90 = x;
  }
  fit.width_10_90 = x90 - x10;
  if (getenv("PCSS_DEBUG"))
    for (int b = 0; b < bins; b += 2)
      if (count[b] > 0)
        std::printf("  s %.2f vis %.3f f %.3f\n", ((b + 0.5) / bins * 2 - 1) * 1.5,
                    sum[b] / count[b], disk_fraction(((b + 0.5) / bins * 2 - 1) * 1.5));
  std::printf(
      "h %.1f theta %.1f: %zu pixels, MAE vs disk-segment %.4f, 10-90 width %.4f "
      "(closed form %.4f)\n",
      h, theta_deg, n, fit.mae, fit.width_10_90, 2 * 0.6870 * half);
  return fit;
}

TEST(Pcss, PenumbraWidensWithTheBlockerDistanceAsGeometryPredicts) {
  const float theta = 16.0f;
  double previous = 0;
  for (float h : {0.5f, 1.0f, 2.0f}) {
    const EdgeFit fit = edge_fit(h, theta);
    const double half = h * std::tan(0.5 * theta * M_PI / 180);
    // The disk-segment profile's 10-90 width is 2 * 0.6870 * half (f(+-0.6870) = 0.9 / 0.1).
    EXPECT_NEAR(fit.width_10_90, 2 * 0.6870 * half, 0.15 * 2 * half) << h;
    EXPECT_LT(fit.mae, 0.025) << h;  // measured 0.013
    EXPECT_GT(fit.width_10_90, 1.6 * previous) << h;
    previous = fit.width_10_90;
  }
}

}  // namespace
}  // namespace shadow
