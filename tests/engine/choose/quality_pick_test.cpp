// A quality goal's pick as pure math (issue 17), without OpenCL: the calibration table's format
// (round trip, the built-in table, every malformed input named), and the technique and size a
// goal gets for a table of goals over the street under a sun, with a cost the test controls.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "engine/choose/auto_pick.hpp"
#include "engine/choose/calibration.hpp"
#include "engine/choose/quality_pick.hpp"
#include "engine/plan/cost.hpp"
#include "engine/plan/plan.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

// What every table ends with: the error margins (`errors`, none by default), then the time
// side: each rate at admission's figure, measured on nothing, and the candidates' margins.
std::string times_section(double margin = 1.5, const std::string& errors = "") {
  std::string s = "error_margin,value,views\n" + errors + "device_time,value,measured_on\n";
  for (size_t r = 0; r < kCostRates; ++r)
    s += std::string(cost_rate_label(CostRate(r))) + "," + std::to_string(admission_rates().ns[r]) +
         ",0\n";
  for (const char* t : {"uniform", "lispsm", "psm"})
    s += std::string("margin_p90.") + t + "," + std::to_string(margin) + ",3\n";
  return s;
}

std::string parse_error(const std::string& text) {
  try {
    Calibration::parse(text, "t.csv");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(Calibration, RoundTripsAndNamesEveryMalformedLine) {
  const Calibration& built_in = Calibration::built_in();
  for (Technique t : {Technique::kUniform, Technique::kLispsm, Technique::kPsm}) {
    ASSERT_TRUE(built_in.has(t)) << technique_label(t);
    const std::vector<CalibrationBin>& bins = built_in.table().at(t);
    ASSERT_GE(bins.size(), 2u);
    EXPECT_TRUE(std::isinf(bins.back().footprint_max));
    for (const CalibrationBin& b : bins) EXPECT_GT(b.pixels, 0u) << b.footprint_max;
  }
  const Calibration again = Calibration::parse(built_in.to_csv("a comment\nof two lines"), "x");
  ASSERT_EQ(again.table().size(), built_in.table().size());
  for (const auto& [t, bins] : built_in.table()) {
    const std::vector<CalibrationBin>& back = again.table().at(t);
    ASSERT_EQ(back.size(), bins.size());
    for (size_t i = 0; i < bins.size(); ++i) {
      EXPECT_EQ(back[i].footprint_max, bins[i].footprint_max);
      EXPECT_EQ(back[i].per_boundary, bins[i].per_boundary);
      EXPECT_EQ(back[i].pixels, bins[i].pixels);
    }
  }
  const std::string h = "technique,footprint_px_max,misclassified_per_boundary_pixel,pixels\n";
  const std::string rest = "lispsm,inf,0.3,1\npsm,inf,0.4,1\n" + times_section();
  const Calibration t =
      Calibration::parse(h + "uniform,1,0.01,5\nuniform,4,0.2,5\nuniform,inf,0.5,5\n" + rest, "t");
  EXPECT_EQ(t.per_boundary_at(Technique::kUniform, 0.3), 0.01);
  EXPECT_EQ(t.per_boundary_at(Technique::kUniform, 1.0), 0.01);  // a bin holds its upper edge
  EXPECT_EQ(t.per_boundary_at(Technique::kUniform, 1.5), 0.2);
  EXPECT_EQ(t.per_boundary_at(Technique::kUniform, INFINITY), 0.5);
  EXPECT_EQ(t.per_boundary_at(Technique::kLispsm, 1.5), 0.3);
  EXPECT_EQ(t.per_boundary_at(Technique::kUniform, NAN),
            0.0);  // off every map: nothing is shadowed
  EXPECT_FALSE(t.has(Technique::kCube));
  // A finer map is never predicted worse: rates that fall with the footprint are pooled,
  // weighted by their pixels ((0.02 x 100 + 0.01 x 300) / 400, (0.05 + 0.04) / 2).
  const Calibration pooled = Calibration::parse(
      h + "uniform,1,0.02,100\nuniform,2,0.01,300\nuniform,4,0.05,100\nuniform,inf,0.04,100\n" +
          rest,
      "p");
  EXPECT_DOUBLE_EQ(pooled.per_boundary_at(Technique::kUniform, 0.5), 0.0125);
  EXPECT_DOUBLE_EQ(pooled.per_boundary_at(Technique::kUniform, 1.5), 0.0125);
  EXPECT_DOUBLE_EQ(pooled.per_boundary_at(Technique::kUniform, 3.0), 0.045);
  EXPECT_DOUBLE_EQ(pooled.per_boundary_at(Technique::kUniform, INFINITY), 0.045);
  EXPECT_EQ(pooled.table().at(Technique::kUniform)[1].per_boundary, 0.01);  // kept as measured
  // Bins on fewer than kMinBinPixels take the next coarser dense bin's rate, else the nearest
  // finer one's: a 0 on 7 pixels promises no perfect map.
  const Calibration sparse = Calibration::parse(
      h + "uniform,0.5,0,7\nuniform,1,0.2,20000\nuniform,4,0.1,50\nuniform,inf,0.5,30000\n" +
          "lispsm,1,0.3,20000\nlispsm,inf,0.9,3\npsm,inf,0.4,1\n" + times_section(),
      "s");
  EXPECT_EQ(sparse.per_boundary_at(Technique::kUniform, 0.3), 0.2);
  EXPECT_EQ(sparse.per_boundary_at(Technique::kUniform, 1.0), 0.2);
  EXPECT_EQ(sparse.per_boundary_at(Technique::kUniform, 3.0), 0.5);
  EXPECT_EQ(sparse.per_boundary_at(Technique::kUniform, 5.0), 0.5);
  EXPECT_EQ(sparse.per_boundary_at(Technique::kLispsm, 5.0), 0.3);
  EXPECT_EQ(sparse.per_boundary_at(Technique::kPsm, 5.0), 0.4);  // no dense bin: as measured
  // PSM_CUBE's faces are PSM maps: with no coarser dense bin of its own it takes PSM's rate.
  const Calibration cube = Calibration::parse(
      h + "uniform,inf,0.5,30000\nlispsm,inf,0.3,20000\npsm,2,0.1,20000\npsm,8,0.6,50\n" +
          "psm,inf,0.8,20000\npsm_cube,2,0.05,20000\npsm_cube,8,0.07,9\npsm_cube,inf,0.9,4\n" +
          times_section(),
      "c");
  EXPECT_EQ(cube.per_boundary_at(Technique::kPsmCube, 1.0), 0.05);
  EXPECT_EQ(cube.per_boundary_at(Technique::kPsmCube, 5.0), 0.8);  // PSM's next dense bin
  EXPECT_EQ(cube.per_boundary_at(Technique::kPsmCube, 50.0), 0.8);
  EXPECT_EQ(sparse.table().at(Technique::kUniform)[0].per_boundary, 0.0);  // kept as measured
  for (const auto& [technique, bins] : built_in.table()) {
    double last = 0;
    for (double f = 1.0 / 32; f < 1e4; f *= 1.5) {
      EXPECT_GE(built_in.per_boundary_at(technique, f), last)
          << technique_label(technique) << " " << f;
      last = built_in.per_boundary_at(technique, f);
    }
  }

  EXPECT_EQ(parse_error(""), "t.csv: no header (an empty file?)");
  EXPECT_EQ(parse_error("# only a comment\n"), "t.csv: no header (an empty file?)");
  EXPECT_NE(parse_error("footprint,rate\n").find("t.csv:1: expected the header"),
            std::string::npos);
  EXPECT_EQ(parse_error(h + "uniform,1,0.1\n"), "t.csv:2: expected 4 comma-separated fields");
  EXPECT_EQ(parse_error(h + "uniform,1,0.1,3,4\n"), "t.csv:2: expected 4 comma-separated fields");
  EXPECT_EQ(
      parse_error(h + "spot,1,0.1,3\n"),
      "t.csv:2: unknown technique \"spot\" (expected uniform, lispsm, psm, psm_cube or cube)");
  EXPECT_EQ(parse_error(h + "uniform,abc,0.1,3\n"),
            "t.csv:2: footprint_px_max must be a number > 0 or inf");
  EXPECT_EQ(parse_error(h + "uniform,2,0.1,3\nuniform,1,0.2,3\n"),
            "t.csv:3: footprint_px_max must increase from row to row");
  EXPECT_EQ(parse_error(h + "uniform,1,-0.5,3\n"),
            "t.csv:2: misclassified_per_boundary_pixel must be a number >= 0");
  EXPECT_EQ(parse_error(h + "uniform,1,nan,3\n"),
            "t.csv:2: misclassified_per_boundary_pixel must be a number >= 0");
  EXPECT_EQ(parse_error(h + "uniform,1,inf,3\n"),
            "t.csv:2: misclassified_per_boundary_pixel must be a number >= 0");
  // More misclassified pixels than boundary pixels: a view whose edges are all badly resolved.
  EXPECT_NO_THROW(Calibration::parse(h + "uniform,inf,1.5,3\n" + rest, "t"));
  EXPECT_EQ(parse_error("technique,footprint_px_max,misclassified_rate,pixels\n" + rest),
            "t.csv:1: a table per pixel, from before the boundary probe: write a new one with "
            "shadow-bench --calibration");
  EXPECT_EQ(parse_error(h + "uniform,1,0.1,-3\n"), "t.csv:2: pixels must be a whole number >= 0");
  EXPECT_EQ(parse_error(h + "uniform,1,0.1,3\n" + rest),
            "t.csv:3: the bins before this line do not end with footprint_px_max inf");
  EXPECT_EQ(
      parse_error(h + "uniform,inf,0.1,3\nlispsm,inf,0.3,1\npsm,inf,0.4,1\nuniform,inf,0.1,3\n"),
      "t.csv:5: technique uniform's rows are not together");
  EXPECT_EQ(parse_error(h + "uniform,inf,0.1,3\nlispsm,inf,0.1,3\n"),
            "t.csv: no bins for psm (the quality goals' candidates need uniform, lispsm and psm)");
  EXPECT_EQ(parse_error(h + "uniform,1,0.1,3\r\nuniform,inf,0.2,3\r\n" + rest),
            "(accepted)");  // CRLF files
  try {
    Calibration::load("/nonexistent/calibration.csv");
    ADD_FAILURE() << "a missing file loaded";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/calibration.csv: cannot be read"),
              std::string::npos)
        << e.what();
  }
}

// The time side: typical rates and their margins round-trip; every malformed row is named; a
// candidate is predicted at the table's rates times its technique's margin.
TEST(Calibration, DeviceTimesRoundTripAndPredict) {
  const Calibration& built_in = Calibration::built_in();
  const DeviceTimes& times = built_in.times();
  for (Technique t : {Technique::kUniform, Technique::kLispsm, Technique::kPsm}) {
    ASSERT_TRUE(times.margins.count(t)) << technique_label(t);
    EXPECT_GT(times.margins.at(t).cases, 0u);
    EXPECT_GE(times.margins.at(t).p90, 1.0);  // a 90th percentile of measured over typical time
  }
  for (CostRate r : {CostRate::kTriangle, CostRate::kMapTexel, CostRate::kViewPixel,
                     CostRate::kDensityPixel, CostRate::kTestPixel}) {
    EXPECT_GT(times.measured_on[size_t(r)], 0u) << cost_rate_label(r);  // the sweep measures them
    EXPECT_GT(times.rates[r], 0.0) << cost_rate_label(r);
    // Where admission errs high on purpose, typical rates sit below (measured at 0.15-0.65 of
    // it); the texel density and the hard test are priced near what they cost.
    if (r != CostRate::kTestPixel && r != CostRate::kDensityPixel) {
      EXPECT_LT(times.rates[r], admission_rates()[r]) << cost_rate_label(r);
    }
  }
  // What the hard-test sweep never runs keeps admission's rate.
  EXPECT_EQ(times.measured_on[size_t(CostRate::kTap)], 0u);
  EXPECT_EQ(times.rates[CostRate::kTap], admission_rates()[CostRate::kTap]);
  const Calibration again = Calibration::parse(built_in.to_csv("c"), "x");
  for (size_t r = 0; r < kCostRates; ++r) {
    EXPECT_NEAR(again.times().rates.ns[r], times.rates.ns[r], 1e-5 * times.rates.ns[r]);
    EXPECT_EQ(again.times().measured_on[r], times.measured_on[r]);
  }
  ASSERT_EQ(again.times().margins.size(), times.margins.size());
  for (const auto& [t, m] : times.margins) {
    EXPECT_NEAR(again.times().margins.at(t).p90, m.p90, 1e-5);
    EXPECT_EQ(again.times().margins.at(t).cases, m.cases);
  }
  // Every size a goal may pick has its own factors for every candidate technique.
  for (Technique t : {Technique::kUniform, Technique::kLispsm, Technique::kPsm})
    for (uint32_t size : kQualitySizes) {
      const auto it = times.sized.find({t, size});
      ASSERT_NE(it, times.sized.end()) << technique_label(t) << " " << size;
      EXPECT_GE(it->second.cases, DeviceTimes::kMinSizedCases);
      EXPECT_LE(it->second.median, it->second.p90);
    }
  ASSERT_EQ(again.times().sized.size(), times.sized.size());
  for (const auto& [key, m] : times.sized) {
    EXPECT_NEAR(again.times().sized.at(key).median, m.median, 1e-5);
    EXPECT_NEAR(again.times().sized.at(key).p90, m.p90, 1e-5);
    EXPECT_EQ(again.times().sized.at(key).cases, m.cases);
  }

  // Only the view's pixels priced, at 10 ns: 320 x 180 x 10 ns = 0.576 ms for the camera view and
  // as much for the texel density, times uniform's margin of 2 (LiSPSM's 3; PSM cubes, with no
  // margin of their own, take the largest).
  std::string rates = "error_margin,value,views\ndevice_time,value,measured_on\n";
  for (size_t r = 0; r < kCostRates; ++r) {
    const CostRate rate = CostRate(r);
    const bool priced = rate == CostRate::kViewPixel || rate == CostRate::kDensityPixel;
    rates += std::string(cost_rate_label(rate)) + (priced ? ",10,4\n" : ",0,4\n");
  }
  const std::string bins =
      "technique,footprint_px_max,misclassified_per_boundary_pixel,pixels\n"
      "uniform,inf,0.1,1\nlispsm,inf,0.1,1\npsm,inf,0.1,1\n";
  const std::string margins = "margin_p90.uniform,2,9\nmargin_p90.lispsm,3,9\nmargin_p90.psm,1,9\n";
  const Calibration priced = Calibration::parse(bins + rates + margins, "p");
  RenderRequest r;
  r.scene = std::make_shared<Scene>();
  r.camera.width = 320, r.camera.height = 180;
  r.products = {Product::kVisibility, Product::kTexelDensity};
  EXPECT_NEAR(priced.predict_time(r, make_plan(r)).typical_ms, 1.152, 1e-9);
  EXPECT_NEAR(priced.predict_time(r, make_plan(r)).p90_ms, 2 * 1.152, 1e-9);
  r.shadow_map.technique = Technique::kLispsm;
  EXPECT_NEAR(priced.predict_time(r, make_plan(r)).typical_ms, 1.152, 1e-9);
  EXPECT_NEAR(priced.predict_time(r, make_plan(r)).p90_ms, 3 * 1.152, 1e-9);
  r.shadow_map.technique = Technique::kPsmCube;
  EXPECT_NEAR(priced.predict_time(r, make_plan(r)).p90_ms, 3 * 1.152, 1e-9);
  // A technique's factors at a size measured on enough cases: the median for the typical time.
  const Calibration by_size = Calibration::parse(
      bins + rates + margins + "margin_median.lispsm.1024,0.5,5\nmargin_p90.lispsm.1024,4,5\n" +
          "margin_median.lispsm.2048,2,4\nmargin_p90.lispsm.2048,8,4\n",
      "s");
  r.shadow_map.technique = Technique::kLispsm;
  r.shadow_map.size = 1024;
  EXPECT_NEAR(by_size.predict_time(r, make_plan(r)).typical_ms, 0.5 * 1.152, 1e-9);
  EXPECT_NEAR(by_size.predict_time(r, make_plan(r)).p90_ms, 4 * 1.152, 1e-9);
  r.shadow_map.size = 2048;  // 4 cases are too few: the technique's margin
  EXPECT_NEAR(by_size.predict_time(r, make_plan(r)).typical_ms, 1.152, 1e-9);
  EXPECT_NEAR(by_size.predict_time(r, make_plan(r)).p90_ms, 3 * 1.152, 1e-9);
  EXPECT_EQ(by_size.to_csv("").find("margin_median.lispsm.1024,0.5,5\nmargin_p90.lispsm.1024,4,5"),
            by_size.to_csv("").find("margin_median.lispsm.1024"));

  const std::string t = bins + "error_margin,value,views\ndevice_time,value,measured_on\n";
  EXPECT_EQ(parse_error(bins),
            "t.csv: no \"device_time,value,measured_on\" rows (a table from "
            "before the time side): write a new one with shadow-bench "
            "--calibration");
  EXPECT_EQ(parse_error(t + "triangle,1\n"), "t.csv:7: expected 3 comma-separated fields");
  EXPECT_EQ(parse_error(t + "pixel,1,2\n"), "t.csv:7: unknown device_time \"pixel\"");
  EXPECT_EQ(parse_error(t + "triangle,1,2\ntriangle,1,2\n"), "t.csv:8: triangle twice");
  EXPECT_EQ(parse_error(t + "triangle,-1,2\n"), "t.csv:7: triangle must be a number >= 0");
  EXPECT_EQ(parse_error(t + "triangle,nan,2\n"), "t.csv:7: triangle must be a number >= 0");
  EXPECT_EQ(parse_error(t + "triangle,1,2.5\n"),
            "t.csv:7: measured_on must be a whole number >= 0");
  EXPECT_EQ(parse_error(t + "margin_p90.psm,0,2\n"),
            "t.csv:7: margin_p90.psm must be a number > 0");
  EXPECT_EQ(parse_error(t + "margin_p90.psm,1,2\nmargin_p90.psm,1,2\n"),
            "t.csv:8: margin_p90.psm twice");
  EXPECT_EQ(parse_error(t + "margin_p90.spot,1,2\n"),
            "t.csv:7: unknown technique in \"margin_p90.spot\" (expected uniform, lispsm, psm, "
            "psm_cube or cube)");
  EXPECT_EQ(parse_error(t + "margin_p90.psm,1,2\n"),
            "t.csv: no device_time row for triangle (a table from before that rate: write a new "
            "one with shadow-bench --calibration)");
  EXPECT_EQ(parse_error(t + "margin_median.psm,1,2\n"),
            "t.csv:7: margin_median.psm needs a map size (margin_median.<technique>.<size>)");
  EXPECT_EQ(parse_error(t + "margin_p90.psm.big,1,2\n"),
            "t.csv:7: bad map size in \"margin_p90.psm.big\" (a whole number in [1, 8192])");
  EXPECT_EQ(parse_error(t + "margin_p90.psm.512,1,2\nmargin_p90.psm.512,1,2\n"),
            "t.csv:8: margin_p90.psm.512 twice");
  EXPECT_EQ(parse_error(t + "margin_p90.psm.512,1,2\nmargin_median.psm.512,1,3\n"),
            "t.csv:8: margin_median.psm.512: its median and 90th percentile count different cases");
  EXPECT_EQ(parse_error(bins + rates + margins + "margin_median.psm.512,1,2\n"),
            "t.csv: margin_median.psm.512 without its margin_p90 row");
  EXPECT_EQ(parse_error(bins + rates + "margin_p90.uniform,2,9\nmargin_p90.psm,1,9\n"),
            "t.csv: no device_time row for margin_p90.lispsm");
  // Bins after the time side begin are time rows: three fields.
  EXPECT_EQ(parse_error(t + "uniform,inf,0.1,1\n"), "t.csv:7: expected 3 comma-separated fields");
}

// The street of auto_pick_test, seen by a walker, the sun from the side.
std::vector<InstanceBounds> street() {
  std::vector<InstanceBounds> v = {{Bounds{{-40, -1, -300}, {40, 0, 10}}, true, true}};
  for (int k = 0; k < 12; ++k)
    for (double x : {-14.0, 8.0})
      v.push_back({Bounds{{x, 0, -20.0 * k - 12}, {x + 6, 9, -20.0 * k - 4}}, true, true});
  return v;
}

RenderRequest walker(Quality::Goal goal, double value) {
  RenderRequest r;
  r.camera.eye = {0, 1.7f, 0};
  r.camera.target = {0, 1.2f, -20};
  r.camera.width = 320, r.camera.height = 180;
  r.camera.near = 0.1f, r.camera.far = 300;
  r.lights[0].direction = glm::normalize(glm::vec3(1, -1, -0.3f));
  r.products = {Product::kVisibility};
  r.quality = {goal, value};
  return r;
}

// Error falls with finer texels: at the walker's 2% boundary share, 0.1% at <= 0.5 px, 1% at
// <= 2 px, 5% beyond.
const Calibration& steps() {
  static const Calibration c = Calibration::parse(
      "technique,footprint_px_max,misclassified_per_boundary_pixel,pixels\n"
      "uniform,0.5,0.05,1\nuniform,2,0.5,1\nuniform,inf,2.5,1\n"
      "lispsm,0.5,0.05,1\nlispsm,2,0.5,1\nlispsm,inf,2.5,1\n"
      "psm,0.5,0.05,1\npsm,2,0.5,1\npsm,inf,2.5,1\n" +
          times_section(),
      "steps");
  return c;
}
const std::vector<double> kWalkerBoundary = {0.02};  // the probe's share, one light

// What a probe measured, as these tests give it: no depth range (PSM and LiSPSM fitted to the
// receivers' boxes alone) and, without `weights`, every sample alike.
ProbeMeasure measure(std::vector<double> boundary, std::vector<Sample> samples,
                     std::vector<std::vector<double>> weights = {}) {
  ProbeMeasure m;
  m.boundary = std::move(boundary);
  m.samples = std::move(samples);
  m.weights = std::move(weights);
  return m;
}

// pick_quality on the calibration above, with the receivers' boxes standing in for the probe's
// samples of the camera view.
QualityPick pick(const RenderRequest& r, const std::vector<InstanceBounds>& scene,
                 const std::vector<double>& boundary, const CandidateCost& cost) {
  return pick_quality(r, scene, measure(boundary, receiver_samples(r.camera, scene)), steps(),
                      cost);
}

// Device time grows with the map's texels; LiSPSM and PSM a little dearer than uniform, and
// their 90th percentile much further above it (margins 3 against 1.5).
std::optional<CandidatePrice> texel_cost(const RenderRequest& r, const MapLoads& = {}) {
  const double texels = double(r.shadow_map.size) * r.shadow_map.size;
  const bool uniform = r.shadow_map.technique == Technique::kUniform;
  const double typical = 10 + texels / 1e6 * 8 + (uniform ? 0 : 2);
  return CandidatePrice{make_plan(r), PredictedTime{typical, typical * (uniform ? 1.5 : 3)}};
}

TEST(QualityPick, GoalsPickTheirTechniqueAndSizeDeterministically) {
  const std::vector<InstanceBounds> scene = street();
  const QualityPick loose =
      pick(walker(Quality::Goal::kMaxError, 1.0), scene, kWalkerBoundary, texel_cost);
  const std::vector<QualityCandidate>& all = loose.candidates;
  ASSERT_EQ(all.size(), 12u);  // uniform, lispsm, psm x 512..4096
  std::printf("candidates: %s\n", loose.reason.c_str());
  // Predicted error falls (or stays) as the map grows, per technique.
  for (size_t i = 0; i + 1 < all.size(); ++i)
    if (all[i].technique == all[i + 1].technique) {
      EXPECT_GE(all[i].predicted_error, all[i + 1].predicted_error);
    }
  // Any error allowed: the cheapest.
  EXPECT_EQ(loose.technique, Technique::kUniform);
  EXPECT_EQ(loose.size, 512u);
  EXPECT_TRUE(loose.goal_met);
  // Each bound between the candidates' errors gets the cheapest candidate under it.
  for (const QualityCandidate& bound : all) {
    const QualityPick p = pick(walker(Quality::Goal::kMaxError, bound.predicted_error), scene,
                               kWalkerBoundary, texel_cost);
    EXPECT_TRUE(p.goal_met);
    EXPECT_LE(p.predicted_error, bound.predicted_error);
    const auto chosen = *std::find_if(all.begin(), all.end(), [&](const QualityCandidate& c) {
      return c.technique == p.technique && c.size == p.size;
    });
    for (const QualityCandidate& c : all)
      if (c.predicted_error <= bound.predicted_error) {
        EXPECT_LE(chosen.typical_device_ms, c.typical_device_ms);
      }
    // The same pick every time.
    const QualityPick again = pick(walker(Quality::Goal::kMaxError, bound.predicted_error), scene,
                                   kWalkerBoundary, texel_cost);
    EXPECT_EQ(again.technique, p.technique);
    EXPECT_EQ(again.size, p.size);
  }
  // Below every candidate: the most accurate, not met.
  double best = INFINITY;
  for (const QualityCandidate& c : all) best = std::min(best, c.predicted_error);
  const QualityPick tight =
      pick(walker(Quality::Goal::kMaxError, best / 2), scene, kWalkerBoundary, texel_cost);
  EXPECT_FALSE(tight.goal_met);
  EXPECT_EQ(tight.predicted_error, best);
  // A time budget: the most accurate that fits; under every candidate's time: the fastest.
  const QualityPick budget =
      pick(walker(Quality::Goal::kMaxDeviceMs, 30), scene, kWalkerBoundary, texel_cost);
  EXPECT_TRUE(budget.goal_met);
  EXPECT_LE(budget.predicted_device_ms, 30);
  for (const QualityCandidate& c : all)
    if (c.predicted_device_ms <= 30) {
      EXPECT_LE(budget.predicted_error, c.predicted_error);
    }
  const QualityPick broke =
      pick(walker(Quality::Goal::kMaxDeviceMs, 1), scene, kWalkerBoundary, texel_cost);
  EXPECT_FALSE(broke.goal_met);
  EXPECT_EQ(broke.technique, Technique::kUniform);
  EXPECT_EQ(broke.size, 512u);
}

// A sample on a side facing away from the light, or edge-on to it, is an attached shadow, which
// no map misclassifies: it predicts no error, but counts in the mean over the view.
TEST(QualityPick, SidesFacingAwayFromTheLightPredictNoError) {
  const std::vector<InstanceBounds> scene = street();
  const RenderRequest r = walker(Quality::Goal::kMaxError, 0.01);
  ASSERT_EQ(r.lights[0].type, LightType::kDirectional);
  const glm::dvec3 travel = glm::normalize(glm::dvec3(r.lights[0].direction));
  const std::vector<Sample> seen = receiver_samples(r.camera, scene);
  ASSERT_FALSE(seen.empty());
  std::vector<Sample> away = seen, edge_on = seen;
  for (Sample& s : away) s.n = travel;
  for (Sample& s : edge_on) s.n = glm::normalize(glm::cross(travel, glm::dvec3(0, 0, 1)));
  const auto errors = [&](const std::vector<Sample>& samples) {
    std::vector<double> e;
    for (const QualityCandidate& c :
         pick_quality(r, scene, measure(kWalkerBoundary, samples), steps(), texel_cost).candidates)
      e.push_back(c.predicted_error);
    return e;
  };
  std::vector<Sample> both = seen;
  both.insert(both.end(), away.begin(), away.end());
  const std::vector<double> lit = errors(seen), none = errors(away), flat = errors(edge_on),
                            half = errors(both);
  for (size_t k = 0; k < lit.size(); ++k) {
    EXPECT_GT(lit[k], 0.0) << k;
    EXPECT_EQ(none[k], 0.0) << k;
    EXPECT_EQ(flat[k], 0.0) << k;
    EXPECT_NEAR(half[k], lit[k] / 2, 1e-12 * lit[k]) << k;
  }
}

// An error bound ranks the candidates that meet it by typical time, not by the 90th percentile
// (a technique with a wide margin is not dearer on average); a budget holds them to the 90th.
TEST(QualityPick, ErrorBoundsRankByTypicalTimeBudgetsByTheNinetiethPercentile) {
  const std::vector<QualityCandidate> candidates = {
      {Technique::kUniform, 1024, 0.004, 12.0, 8.0},  // typical 8, p90 12 (margin 1.5)
      {Technique::kLispsm, 512, 0.004, 15.0, 5.0},    // typical 5, p90 15 (margin 3)
  };
  const Quality error{Quality::Goal::kMaxError, 0.005};
  EXPECT_EQ(&choose_candidate(candidates, error), &candidates[1]);
  // A budget of 13 ms: only uniform's 90th percentile fits, though LiSPSM is faster typically.
  const Quality budget{Quality::Goal::kMaxDeviceMs, 13};
  EXPECT_EQ(&choose_candidate(candidates, budget), &candidates[0]);
  // Under every 90th percentile: the fastest by it.
  const Quality broke{Quality::Goal::kMaxDeviceMs, 1};
  EXPECT_EQ(&choose_candidate(candidates, broke), &candidates[0]);
}

// The probe's boundary share scales every prediction; with several lights the worst decides; a
// view without shadow edges predicts no error and gets the cheapest candidate.
TEST(QualityPick, PredictionsScaleWithTheProbesBoundaryShare) {
  const std::vector<InstanceBounds> scene = street();
  const RenderRequest r = walker(Quality::Goal::kMaxError, 0.01);
  const auto candidates = [&](const RenderRequest& request, std::vector<double> boundary) {
    return pick(request, scene, boundary, texel_cost).candidates;
  };
  const QualityPick flat = pick(r, scene, {0.0}, texel_cost);
  const std::vector<QualityCandidate> base = candidates(r, {0.02}), doubled = candidates(r, {0.04}),
                                      &none = flat.candidates;
  RenderRequest pair = r;
  pair.lights.push_back(pair.lights[0]);
  const std::vector<QualityCandidate> two = candidates(pair, {0.01, 0.04});
  ASSERT_EQ(base.size(), 12u);
  ASSERT_EQ(doubled.size(), 12u);
  ASSERT_EQ(none.size(), 12u);
  ASSERT_EQ(two.size(), 12u);
  bool some_error = false;
  for (size_t i = 0; i < base.size(); ++i) {
    EXPECT_DOUBLE_EQ(doubled[i].predicted_error, 2 * base[i].predicted_error);
    EXPECT_DOUBLE_EQ(two[i].predicted_error,
                     2 * base[i].predicted_error);  // the same light twice: the worst share
    EXPECT_EQ(none[i].predicted_error, 0.0);
    some_error |= base[i].predicted_error > 0;
  }
  EXPECT_TRUE(some_error);
  EXPECT_TRUE(flat.goal_met);
  EXPECT_EQ(flat.technique, Technique::kUniform);
  EXPECT_EQ(flat.size, 512u);
  EXPECT_NE(flat.reason.find("boundary share 0.00%"), std::string::npos) << flat.reason;
}

// Each sample's rate is weighed by the probe's boundary pixels in its cell: a prediction is the
// weighted mean of what each sample alone predicts (its weight alone), scaled by the share; no
// weights, equal ones or all zero (edges only where no sample is seen) give the plain mean.
TEST(QualityPick, SamplesAreWeighedByTheEdgesInTheirCells) {
  const std::vector<InstanceBounds> scene = street();
  const RenderRequest r = walker(Quality::Goal::kMaxError, 0.01);
  const std::vector<Sample> samples = receiver_samples(r.camera, scene);
  ASSERT_GT(samples.size(), 20u);
  const auto errors = [&](std::vector<double> weights) {
    ProbeMeasure probe = measure(kWalkerBoundary, samples);
    if (!weights.empty()) probe.weights = {std::move(weights)};
    std::vector<double> e;
    for (const QualityCandidate& c : pick_quality(r, scene, probe, steps(), texel_cost).candidates)
      e.push_back(c.predicted_error);
    return e;
  };
  const std::vector<double> plain = errors({});
  ASSERT_EQ(plain.size(), 12u);
  const std::vector<double> ones = errors(std::vector<double>(samples.size(), 1.0)),
                            zeros = errors(std::vector<double>(samples.size(), 0.0));
  for (size_t i = 0; i < plain.size(); ++i) {
    EXPECT_DOUBLE_EQ(ones[i], plain[i]);
    EXPECT_DOUBLE_EQ(zeros[i], plain[i]);
  }
  std::vector<std::vector<double>> alone;  // per sample, each candidate's error
  for (size_t j = 0; j < samples.size(); ++j) {
    std::vector<double> w(samples.size(), 0.0);
    w[j] = 1;
    alone.push_back(errors(w));
  }
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> count(0, 40);
  std::vector<double> w(samples.size());
  double total = 0;
  for (double& x : w) total += x = count(rng);
  const std::vector<double> weighed = errors(w);
  bool differs = false;  // the weights move some prediction
  for (size_t i = 0; i < plain.size(); ++i) {
    double want = 0;
    for (size_t j = 0; j < samples.size(); ++j) want += w[j] * alone[j][i];
    EXPECT_NEAR(weighed[i], want / total, 1e-12 * plain[i]) << i;
    differs |= std::abs(weighed[i] - plain[i]) > 0.05 * plain[i];
  }
  EXPECT_TRUE(differs);
  std::vector<double> near(samples.size(), 0.0), far = near;  // the nearest and farthest third
  std::vector<size_t> order(samples.size());
  for (size_t j = 0; j < order.size(); ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return glm::length(samples[a].p - glm::dvec3(r.camera.eye)) <
           glm::length(samples[b].p - glm::dvec3(r.camera.eye));
  });
  for (size_t j = 0; j < order.size() / 3; ++j)
    near[order[j]] = far[order[order.size() - 1 - j]] = 1;
  // Uniform 512's texels are largest on screen near the eye, so edges there err the most.
  EXPECT_GT(errors(near)[0], errors(far)[0]);
  const ProbeMeasure short_of_one =
      measure(kWalkerBoundary, samples, {std::vector<double>(samples.size() - 1)});
  EXPECT_THROW(pick_quality(r, scene, short_of_one, steps(), texel_cost), std::logic_error);
}

// PSM's and LiSPSM's candidates are fitted to the view's depth range where the probe measured
// it, as the run fits them (fitted_matrix); uniform's fit does not read it.
TEST(QualityPick, WarpedCandidatesFitTheProbesDepthRange) {
  const std::vector<InstanceBounds> scene = street();
  const RenderRequest r = walker(Quality::Goal::kMaxError, 0.01);
  const DepthRange range{4.0, 60.0};  // receivers seen from 4 m: LiSPSM's and PSM's near planes
  for (Technique t : {Technique::kUniform, Technique::kLispsm, Technique::kPsm}) {
    EXPECT_EQ(candidate_matrix(r, 0, t, scene, range),
              fitted_matrix(t, r.lights[0], r.camera, scene, range))
        << technique_label(t);
    EXPECT_EQ(candidate_matrix(r, 0, t, scene, std::nullopt),
              fitted_matrix(t, r.lights[0], r.camera, scene, std::nullopt))
        << technique_label(t);
  }
  ProbeMeasure probe = measure(kWalkerBoundary, receiver_samples(r.camera, scene));
  const std::vector<QualityCandidate> boxes =
      pick_quality(r, scene, probe, steps(), texel_cost).candidates;
  probe.depth = range;
  const std::vector<QualityCandidate> fitted =
      pick_quality(r, scene, probe, steps(), texel_cost).candidates;
  ASSERT_EQ(boxes.size(), fitted.size());
  std::set<Technique> moved;
  for (size_t i = 0; i < boxes.size(); ++i)
    if (boxes[i].predicted_error != fitted[i].predicted_error) moved.insert(boxes[i].technique);
  EXPECT_EQ(moved, (std::set<Technique>{Technique::kLispsm, Technique::kPsm}));
}

// Raster loads are measured only where they decide the pick: a goal any map meets takes the
// probe's map, which draws nothing, and measures none; otherwise the chosen technique is
// measured, its candidates priced with their own loads, and the choice made again, so a warp
// whose maps would load the raster heavily loses to what costs less. Each measure costs every
// candidate its time.
TEST(QualityPick, RasterLoadsAreMeasuredWhereTheyDecideThePick) {
  const std::vector<InstanceBounds> scene = street();
  const RenderRequest r = walker(Quality::Goal::kMaxError, 0.01);
  const ProbeMeasure probe = measure(kWalkerBoundary, receiver_samples(r.camera, scene));
  Technique heavy_technique = Technique::kUniform;
  // Per size, one light's load: 1e9 box pixels (1000 ms below) for the heavy technique.
  const auto loads_of = [&](Technique t) {
    std::array<MapLoads, kQualitySizes.size()> loads;
    for (size_t k = 0; k < loads.size(); ++k)
      loads[k] = {{k + 1, t == heavy_technique ? 1'000'000'000u : 0u}};
    return loads;
  };
  std::vector<Technique> measured;
  const CandidateLoads loads{[&](Technique t) {
                               measured.push_back(t);
                               return loads_of(t);
                             },
                             {0.5, 0.75}};
  std::map<std::pair<Technique, uint32_t>, MapLoads> priced_with;
  const auto loaded = [&](const RenderRequest& c, const MapLoads& l) {
    if (!l.empty()) priced_with[{c.shadow_map.technique, c.shadow_map.size}] = l;
    std::optional<CandidatePrice> t = texel_cost(c);
    for (const RasterLoad& one : l) t->time += {one.box_pixels * 1e-6, one.box_pixels * 1e-6};
    return t;
  };

  // Any map meets 100%: the probe's, which draws nothing, so nothing is measured.
  const QualityPick any =
      pick_quality(walker(Quality::Goal::kMaxError, 1.0), scene, probe, steps(), loaded, loads);
  EXPECT_EQ(any.technique, Technique::kUniform);
  EXPECT_EQ(any.size, kQualityProbeSize);
  EXPECT_TRUE(measured.empty());
  for (const QualityCandidate& c : any.candidates)
    EXPECT_EQ(c.raster_load_priced, c.technique == Technique::kUniform && c.size == 512);

  const QualityPick plain = pick_quality(r, scene, probe, steps(), loaded);  // no measures
  EXPECT_TRUE(measured.empty());
  ASSERT_FALSE(plain.technique == Technique::kUniform && plain.size == kQualityProbeSize);
  heavy_technique = plain.technique;
  const QualityPick heavy = pick_quality(r, scene, probe, steps(), loaded, loads);
  ASSERT_FALSE(measured.empty());
  EXPECT_EQ(measured.front(), plain.technique);
  EXPECT_NE(heavy.technique, plain.technique);
  for (size_t i = 0; i < measured.size(); ++i)
    for (size_t j = 0; j < i; ++j) EXPECT_NE(measured[i], measured[j]) << "measured twice";
  const double measures_ms = 0.5 * double(measured.size());
  ASSERT_EQ(heavy.candidates.size(), plain.candidates.size());
  for (size_t i = 0; i < heavy.candidates.size(); ++i) {
    const QualityCandidate &c = heavy.candidates[i], &p = plain.candidates[i];
    const std::string name =
        std::string(technique_label(c.technique)) + " " + std::to_string(c.size);
    const bool was_measured =
        std::find(measured.begin(), measured.end(), c.technique) != measured.end();
    const bool draws_none = c.technique == Technique::kUniform && c.size == kQualityProbeSize;
    EXPECT_EQ(c.raster_load_priced, was_measured || draws_none) << name;
    EXPECT_EQ(c.predicted_error, p.predicted_error) << name;  // the error side is untouched
    const double load_ms = c.technique == plain.technique && !draws_none ? 1000.0 : 0.0;
    EXPECT_NEAR(c.typical_device_ms - p.typical_device_ms, measures_ms + load_ms, 1e-9) << name;
    if (was_measured && !draws_none) {
      const size_t k = size_t(std::find(kQualitySizes.begin(), kQualitySizes.end(), c.size) -
                              kQualitySizes.begin());
      EXPECT_EQ(priced_with.at({c.technique, c.size}), loads_of(c.technique)[k]) << name;
    }
    if (c.technique == heavy.technique && c.size == heavy.size) {
      EXPECT_TRUE(c.raster_load_priced) << "the pick is priced";
    }
  }
}

// The table's error margins: the built-in one has one for every candidate, measured on enough
// views; they round-trip; every malformed row is named; a candidate's predicted error is the
// bins' times its technique and size's margin, where measured on kMinMarginViews views or more.
TEST(QualityPick, ErrorMarginsScaleEachCandidatesPrediction) {
  const Calibration& built_in = Calibration::built_in();
  for (Technique t : {Technique::kUniform, Technique::kLispsm, Technique::kPsm})
    for (uint32_t size : kQualitySizes) {
      const auto it = built_in.error_margins().find({t, size});
      ASSERT_NE(it, built_in.error_margins().end()) << technique_label(t) << " " << size;
      EXPECT_GE(it->second.views, Calibration::kMinMarginViews);
      EXPECT_GT(it->second.value, 0.0);
      EXPECT_EQ(built_in.error_margin(t, size), it->second.value);
    }
  const Calibration again = Calibration::parse(built_in.to_csv("c"), "x");
  ASSERT_EQ(again.error_margins().size(), built_in.error_margins().size());
  for (const auto& [key, m] : built_in.error_margins()) {
    EXPECT_NEAR(again.error_margins().at(key).value, m.value, 1e-5 * m.value);
    EXPECT_EQ(again.error_margins().at(key).views, m.views);
  }

  const std::string bins =
      "technique,footprint_px_max,misclassified_per_boundary_pixel,pixels\n"
      "uniform,0.5,0.05,1\nuniform,2,0.5,1\nuniform,inf,2.5,1\n"
      "lispsm,0.5,0.05,1\nlispsm,2,0.5,1\nlispsm,inf,2.5,1\n"
      "psm,0.5,0.05,1\npsm,2,0.5,1\npsm,inf,2.5,1\n";
  const Calibration scaled =
      Calibration::parse(bins + times_section(1.5, "uniform.1024,2,5\npsm.512,0.5,4\n"), "m");
  EXPECT_EQ(scaled.error_margin(Technique::kUniform, 1024), 2.0);
  EXPECT_EQ(scaled.error_margin(Technique::kPsm, 512), 1.0);      // 4 views are too few
  EXPECT_EQ(scaled.error_margin(Technique::kLispsm, 2048), 1.0);  // none measured
  const std::vector<InstanceBounds> scene = street();
  const RenderRequest r = walker(Quality::Goal::kMaxError, 0.01);
  const ProbeMeasure probe = measure(kWalkerBoundary, receiver_samples(r.camera, scene));
  const std::vector<QualityCandidate>
      plain = pick_quality(r, scene, probe, steps(), texel_cost).candidates,
      with = pick_quality(r, scene, probe, scaled, texel_cost).candidates;
  ASSERT_EQ(plain.size(), 12u);
  ASSERT_EQ(with.size(), 12u);
  for (size_t i = 0; i < plain.size(); ++i) {
    const bool doubled = plain[i].technique == Technique::kUniform && plain[i].size == 1024;
    ASSERT_GT(plain[i].predicted_error, 0.0);
    EXPECT_DOUBLE_EQ(with[i].predicted_error, (doubled ? 2 : 1) * plain[i].predicted_error)
        << technique_label(plain[i].technique) << " " << plain[i].size;
  }

  const std::string e = bins + "error_margin,value,views\n";
  EXPECT_EQ(parse_error(bins + "device_time,value,measured_on\n"),
            "t.csv:11: no \"error_margin,value,views\" section before the device times (a table "
            "from before the error margins): write a new one with shadow-bench --calibration");
  EXPECT_EQ(parse_error(e + "uniform,1,5\n"),
            "t.csv:12: expected <technique>.<size> (uniform, lispsm, psm, psm_cube or cube), got "
            "\"uniform\"");
  EXPECT_EQ(parse_error(e + "spot.512,1,5\n"),
            "t.csv:12: expected <technique>.<size> (uniform, lispsm, psm, psm_cube or cube), got "
            "\"spot.512\"");
  EXPECT_EQ(parse_error(e + "psm.0,1,5\n"),
            "t.csv:12: bad map size in \"psm.0\" (a whole number in [1, 8192])");
  EXPECT_EQ(parse_error(e + "psm.512,-1,5\n"),
            "t.csv:12: the error margin of psm.512 must be a number >= 0");
  EXPECT_EQ(parse_error(e + "psm.512,nan,5\n"),
            "t.csv:12: the error margin of psm.512 must be a number >= 0");
  EXPECT_EQ(parse_error(e + "psm.512,1,2.5\n"), "t.csv:12: views must be a whole number >= 0");
  EXPECT_EQ(parse_error(e + "psm.512,1,5\npsm.512,2,5\n"), "t.csv:13: error margin psm.512 twice");
  EXPECT_EQ(parse_error(e + "psm.512,1\n"), "t.csv:12: expected 3 comma-separated fields");
}

// AUTO with a calibration scores its candidates by their predicted error, the simpler one within
// kErrorTie of the best (relative), and the same every time.
TEST(QualityPick, CalibratedAutoPicksTheLeastPredictedError) {
  RenderRequest r = walker(Quality::Goal::kNone, 0);
  for (float side : {0.2f, 0.7f, 1.5f, 4.0f}) {
    r.lights[0].direction = glm::normalize(glm::vec3(1, -side, -0.3f));
    const AutoPick a = pick_technique(r.lights[0], r.camera, street(), 2048, FilterKind::kHard,
                                      std::nullopt, &steps());
    const AutoPick b = pick_technique(r.lights[0], r.camera, street(), 2048, FilterKind::kHard,
                                      std::nullopt, &steps());
    std::printf("[ auto     ] sun %.1f: %s\n", side, a.reason.c_str());
    EXPECT_EQ(a.reason, b.reason);
    ASSERT_EQ(a.candidates.size(), 3u);
    double best = INFINITY;
    for (const AutoCandidate& c : a.candidates) best = std::min(best, c.predicted_error);
    for (const AutoCandidate& c : a.candidates) {
      if (c.technique == a.technique) {
        EXPECT_LE(c.predicted_error, best * (1 + kErrorTie));
        break;
      }
      EXPECT_GT(c.predicted_error, best * (1 + kErrorTie)) << technique_label(c.technique);
    }
  }
}

TEST(QualityPick, CandidatesFollowTheLightsTheFilterAndTheCost) {
  const std::vector<InstanceBounds> scene = street();
  std::vector<QualityCandidate> all;
  // A spot light: no LiSPSM. The pick is among its candidates.
  RenderRequest spot = walker(Quality::Goal::kMaxError, 0.01);
  spot.lights[0].type = LightType::kSpot;
  spot.lights[0].position = {0, 30, -50};
  spot.lights[0].direction = {0, -1, 0};
  spot.lights[0].cone_angle_deg = 120;
  const QualityPick by_spot = pick(spot, scene, kWalkerBoundary, texel_cost);
  all = by_spot.candidates;
  EXPECT_EQ(&choose_candidate(all, spot.quality) - all.data(),
            std::find_if(all.begin(), all.end(), [&](const QualityCandidate& c) {
              return c.technique == by_spot.technique && c.size == by_spot.size;
            }) - all.begin());
  for (const QualityCandidate& c : all) EXPECT_NE(c.technique, Technique::kLispsm);
  EXPECT_EQ(all.size(), 8u);
  // PCSS: uniform maps only.
  RenderRequest pcss = walker(Quality::Goal::kMaxError, 0.01);
  pcss.filter.kind = FilterKind::kPcss;
  all = pick(pcss, scene, kWalkerBoundary, texel_cost).candidates;
  for (const QualityCandidate& c : all) EXPECT_EQ(c.technique, Technique::kUniform);
  // What the server would refuse is not picked, even when it alone meets the goal.
  const auto small_only = [](const RenderRequest& r,
                             const MapLoads&) -> std::optional<CandidatePrice> {
    if (r.shadow_map.size > 1024) return std::nullopt;
    return texel_cost(r);
  };
  const QualityPick p =
      pick(walker(Quality::Goal::kMaxError, 1e-6), scene, kWalkerBoundary, small_only);
  EXPECT_EQ(p.candidates.size(), 6u);
  EXPECT_LE(p.size, 1024u);
  try {
    pick(walker(Quality::Goal::kMaxError, 0.01), scene, kWalkerBoundary,
         [](const RenderRequest&, const MapLoads&) { return std::optional<CandidatePrice>(); });
    ADD_FAILURE() << "nothing to pick from, yet a pick";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "quality");
  }
}

// What a pick takes from its probe: the maps of uniform 512 without blur classes, and with one
// light and the hard filter the hard test; nothing of any other pick.
TEST(QualityPick, WhatAPickTakesFromItsProbe) {
  RenderRequest r = walker(Quality::Goal::kMaxError, 0.01);
  r.scene = std::make_shared<Scene>();
  QualityPick probe_map{};
  probe_map.technique = Technique::kUniform, probe_map.size = kQualityProbeSize;
  RenderRequest picked = with_pick(r, probe_map);
  const auto taken = [&](StepKind kind) {
    return taken_from_probe(picked, make_plan(picked), kind);
  };
  EXPECT_TRUE(taken(StepKind::kRenderMaps));
  EXPECT_TRUE(taken(StepKind::kVisibility));
  EXPECT_FALSE(taken(StepKind::kCameraView));  // the run takes the probe's view by itself
  EXPECT_FALSE(taken(StepKind::kTexelDensity));
  picked.filter.kind = FilterKind::kPcf2x2;  // the probe tested hard
  EXPECT_TRUE(taken(StepKind::kRenderMaps));
  EXPECT_FALSE(taken(StepKind::kVisibility));
  picked.filter.kind = FilterKind::kHard;
  picked.lights.push_back(picked.lights[0]);  // the probe's test buffer holds the last light's
  EXPECT_TRUE(taken(StepKind::kRenderMaps));
  EXPECT_FALSE(taken(StepKind::kVisibility));
  QualityPick other = probe_map;
  other.technique = Technique::kLispsm;
  picked = with_pick(r, other);
  EXPECT_FALSE(taken(StepKind::kRenderMaps));
  other = probe_map;
  other.size = 2 * kQualityProbeSize;
  picked = with_pick(r, other);
  EXPECT_FALSE(taken(StepKind::kRenderMaps));
}

}  // namespace
}  // namespace shadow
