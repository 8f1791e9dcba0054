// Typical device-time rates fitted to measured steps (engine/plan/cost_fit.hpp), on synthetic steps
// whose true rates are known, and the cost estimate's breakdown that the fit reads.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "engine/plan/cost.hpp"
#include "engine/plan/cost_fit.hpp"
#include "engine/plan/plan.hpp"

namespace shadow {
namespace {

StepTime step(double triangles, double texels, double pixels, const CostRates& truth) {
  StepTime s;
  s.units[size_t(CostRate::kTriangle)] = triangles;
  s.units[size_t(CostRate::kMapTexel)] = texels;
  s.units[size_t(CostRate::kViewPixel)] = pixels;
  for (size_t r = 0; r < kCostRates; ++r) s.ms += s.units[r] * truth.ns[r] * 1e-6;
  return s;
}

CostRates truth() {
  CostRates t;
  t[CostRate::kTriangle] = 60, t[CostRate::kMapTexel] = 0.5, t[CostRate::kViewPixel] = 5;
  return t;
}

// Camera views (triangles, pixels) and maps (triangles, texels) of scenes of several sizes.
std::vector<StepTime> sweep(const CostRates& t) {
  std::vector<StepTime> steps;
  for (double tri : {1e3, 4e4, 2e5})
    for (double size : {512.0, 1024.0, 4096.0}) {
      steps.push_back(step(tri, 0, 640 * 360, t));
      steps.push_back(step(tri, size * size, 0, t));
    }
  return steps;
}

TEST(CostFit, RecoversKnownRatesAndKeepsTheUnmeasured) {
  const RateFit fit = fit_rates(sweep(truth()), admission_rates());
  for (CostRate r : {CostRate::kTriangle, CostRate::kMapTexel, CostRate::kViewPixel}) {
    EXPECT_NEAR(fit.rates[r], truth()[r], 1e-9 * truth()[r]) << cost_rate_label(r);
    EXPECT_GT(fit.steps[size_t(r)], 0u);
  }
  EXPECT_EQ(fit.steps[size_t(CostRate::kTriangle)], 18u);
  EXPECT_EQ(fit.steps[size_t(CostRate::kMapTexel)], 9u);
  EXPECT_EQ(fit.rates[CostRate::kTap], admission_rates()[CostRate::kTap]);
  EXPECT_EQ(fit.steps[size_t(CostRate::kTap)], 0u);

  // Each step measured 10% slow once and 10% fast once: least squares on the relative error
  // weighs the fast one more, (1/0.9 + 1/1.1) / (1/0.81 + 1/1.21) = 0.980 of the truth.
  std::vector<StepTime> noisy;
  for (StepTime s : sweep(truth())) {
    const double ms = s.ms;
    s.ms = 0.9 * ms;
    noisy.push_back(s);
    s.ms = 1.1 * ms;
    noisy.push_back(s);
  }
  const RateFit rough = fit_rates(noisy, admission_rates());
  for (CostRate r : {CostRate::kTriangle, CostRate::kMapTexel, CostRate::kViewPixel})
    EXPECT_NEAR(rough.rates[r], 0.980 * truth()[r], 1e-3 * truth()[r]) << cost_rate_label(r);

  // A step that did not run (0 ms) says nothing.
  std::vector<StepTime> with_idle = sweep(truth());
  with_idle.push_back(step(1e6, 0, 0, truth()));
  with_idle.back().ms = 0;
  EXPECT_NEAR(fit_rates(with_idle, admission_rates()).rates[CostRate::kTriangle], 60, 1e-6);
}

TEST(CostFit, NegativeRatesAreZeroAndInseparableOnesKeepTheFallback) {
  // Maps measured as cheaper with more triangles: the triangle rate would be negative.
  CostRates odd = truth();
  odd[CostRate::kTriangle] = 0;
  std::vector<StepTime> steps;
  for (double tri : {1e3, 1e5})
    for (double size : {512.0, 2048.0}) {
      StepTime s = step(tri, size * size, 0, odd);
      s.ms *= tri > 1e4 ? 0.8 : 1.0;
      steps.push_back(s);
    }
  const RateFit fit = fit_rates(steps, admission_rates());
  EXPECT_EQ(fit.rates[CostRate::kTriangle], 0.0);
  EXPECT_GT(fit.steps[size_t(CostRate::kTriangle)], 0u);
  EXPECT_GT(fit.rates[CostRate::kMapTexel], 0.0);

  // Pixels always 100 per triangle: the steps cannot tell the two rates apart.
  std::vector<StepTime> tied;
  for (double tri : {1e3, 1e4, 1e5}) tied.push_back(step(tri, 0, 100 * tri, truth()));
  const RateFit one = fit_rates(tied, admission_rates());
  EXPECT_EQ(one.steps[size_t(CostRate::kViewPixel)], 0u);
  EXPECT_EQ(one.rates[CostRate::kViewPixel], admission_rates()[CostRate::kViewPixel]);
  // The triangle rate takes the whole time: 60 + 100 x 5 ns per triangle.
  EXPECT_NEAR(one.rates[CostRate::kTriangle], 560, 1e-6);
}

TEST(CostFit, MarginIsTheQuantileOfMeasuredOverPredicted) {
  const std::vector<double> predicted = {10, 10, 10, 10, 10, 10, 10, 10, 10, 10, 0, 10};
  const std::vector<double> measured = {5, 9, 10, 11, 12, 13, 14, 15, 16, 30, 7, NAN};
  EXPECT_DOUBLE_EQ(margin_quantile(predicted, measured, 0.9), 1.6);  // the 9th of 10 ratios
  EXPECT_DOUBLE_EQ(margin_quantile(predicted, measured, 1.0), 3.0);
  EXPECT_DOUBLE_EQ(margin_quantile(predicted, measured, 0.0), 0.5);
  EXPECT_DOUBLE_EQ(margin_quantile({}, {}, 0.9), 1.0);
  // A measured 0 (an error goal's perfect map) is a ratio like any other.
  EXPECT_DOUBLE_EQ(margin_quantile({10, 10}, {0, 10}, 0.5), 0.0);
}

// The breakdown is the estimate: its steps' units priced at the rates give its total.
TEST(CostFit, EstimateIsItsStepsPricedAtItsRates) {
  RenderRequest r;
  r.scene = std::make_shared<Scene>();
  r.camera.width = 640, r.camera.height = 360;
  r.products = {Product::kVisibility, Product::kTexelDensity};
  for (FilterKind f : {FilterKind::kHard, FilterKind::kPcss, FilterKind::kCsm}) {
    r.filter.kind = f;
    const CostEstimate e = estimate_cost(r, make_plan(r));
    double ns = 0;
    for (const StepCost& s : e.steps)
      for (size_t k = 0; k < kCostRates; ++k) ns += s.units[k] * admission_rates().ns[k];
    EXPECT_NEAR(ns * 1e-6, e.ms, 1e-9 * e.ms);
    EXPECT_GT(e.steps.size(), 2u);
  }
}

// A map's raster load enters its light's map step alone, at the load's rates.
TEST(CostFit, RasterLoadsPriceTheirLightsMaps) {
  RenderRequest r;
  r.scene = std::make_shared<Scene>();
  r.camera.width = 640, r.camera.height = 360;
  r.lights.resize(2);
  r.products = {Product::kVisibility};
  const Plan plan = make_plan(r);
  const MapLoads loads = {{1000, 2'000'000}, {30, 40}};
  const CostEstimate without = estimate_cost(r, plan), with = estimate_cost(r, plan, {}, loads);
  ASSERT_EQ(with.steps.size(), without.steps.size());
  size_t maps = 0;
  for (size_t i = 0; i < with.steps.size(); ++i) {
    const StepCost &a = with.steps[i], &b = without.steps[i];
    const bool map = a.step.ends_with("shadow_map");
    const RasterLoad load = !map ? RasterLoad{} : loads.at(a.step.starts_with("light1") ? 1 : 0);
    maps += map;
    EXPECT_EQ(a.units[size_t(CostRate::kTileOverlap)], double(load.overlaps)) << a.step;
    EXPECT_EQ(a.units[size_t(CostRate::kBoxPixel)], double(load.box_pixels)) << a.step;
    EXPECT_EQ(b.units[size_t(CostRate::kBoxPixel)], 0.0) << b.step;
  }
  EXPECT_EQ(maps, 2u);
  CostRates rates;
  rates[CostRate::kTileOverlap] = 3, rates[CostRate::kBoxPixel] = 0.5;
  EXPECT_NEAR(estimate_cost(r, plan, rates, loads).ms, (1030 * 3 + 2'000'040 * 0.5) * 1e-6, 1e-12);
}

}  // namespace
}  // namespace shadow
