// The accuracy side of a quality goal (RenderRequest::quality): how often a camera pixel's hard
// shadow test is wrong, per technique, as a function of the texel footprint there (the size in
// pixels of one map texel on the surface, as PRODUCT_TEXEL_DENSITY measures it), counted per
// pixel on the view's shadow boundaries, over the pixels whose seen side faces the light (the
// others are attached shadows, which no map misclassifies: auto_pick.hpp, faces_light). A view's
// misclassified share is about its boundary share (the probe's, engine/choose/quality_pick.hpp)
// times this at the footprints where its edges lie: views differ far more in how many shadow edges
// they show than in how each edge is resolved (docs/bench/results.md). shadow-bench --calibration
// measures it against the Embree oracle over the standard views and writes it as CSV; the server
// embeds data/calibration.csv and may load another with
// --calibration at start-up.
//
// Format: '#' comment lines, the header
// "technique,footprint_px_max,misclassified_per_boundary_pixel,pixels", then per technique
// (technique_label: uniform, lispsm, psm, psm_cube, cube; each at most once, its rows together)
// one row per bin in increasing footprint_px_max, its last "inf": the bin's misclassified pixels
// over the boundary pixels they stand for (the sum over the bin's pixels of the probe's boundary
// share in the pixel's cell of the goals' sample grid: where the view's edges are, as a goal
// weighs its samples), and how many pixels it was measured on. A footprint
// falls in the first bin whose footprint_px_max holds it.
//
// The error margins follow: the header "error_margin,value,views", then per technique and map
// size at most one row "<technique>.<size>": a goal's candidate's measured misclassified share
// over its prediction from the bins, at kErrorQuantile of the views it was measured on
// (ErrorMargin), and on how many.
//
// The time side follows: the header "device_time,value,measured_on", then one row per cost rate
// (cost_rate_label, each exactly once): its typical nanoseconds per unit, fitted to the measured
// passes of the cases (cost_fit.hpp), and on how many steps (0: not measured, admission's rate
// kept); then per technique (uniform, lispsm and psm at least) "margin_p90.<technique>":
// measured over predicted device time at the 90th percentile of its cases, and how many; then
// per technique and map size that ran "margin_median.<technique>.<size>" and
// "margin_p90.<technique>.<size>", both or neither. A goal's candidate is predicted at these
// rates times the factors of its technique and size (DeviceTimes::factors).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "engine/plan/cost.hpp"
#include "wire/types.hpp"

namespace shadow {

struct CalibrationBin {
  double footprint_max = 0;  // px; +inf for the last
  double per_boundary = 0;   // misclassified pixels per boundary pixel, >= 0
  uint64_t pixels = 0;
};

// A request's device time as the calibration predicts it.
struct PredictedTime {
  double typical_ms = 0;  // at the typical rates
  double p90_ms = 0;      // typical times the technique's margin
  PredictedTime& operator+=(const PredictedTime& o) {
    typical_ms += o.typical_ms, p90_ms += o.p90_ms;
    return *this;
  }
};

// Why the error side needs margins besides its bins: the bins pool pixels across views, and a
// view's pixels of small footprint are not a random sample of its pixels (they lie near the eye,
// or face the light squarely), so the pooled rates grow with the footprint more slowly than one
// view's error does as its map's edge doubles (about half per doubling). Predicted from the
// bins alone, 512^2 maps came out too accurate and 4096^2 ones too poor (measured over predicted,
// median over the standard views: uniform 1.31 at 512, 0.59 at 4096; LiSPSM 1.45 and 0.56).
// Refitting the bins to whole views did not remove that (the views differ in more than their
// footprints), so the margin is per technique and size, like the time side's. It is taken at
// kErrorQuantile rather than the median because a max_error request asks for a bound: at the
// median half the views would miss it.
struct ErrorMargin {
  double value = 1;  // measured over predicted misclassified share, >= 0
  uint64_t views = 0;
};
using ErrorMargins = std::map<std::pair<Technique, uint32_t>, ErrorMargin>;
inline constexpr double kErrorQuantile = 0.7;

struct DeviceTimes {
  struct Margin {
    double p90 = 1;  // measured over predicted device time, 90th percentile of the cases
    uint64_t cases = 0;
  };
  CostRates rates;
  std::array<uint64_t, kCostRates> measured_on{};  // steps per rate; 0: admission's rate
  // Per technique that ran (warped maps' raster time varies far more with the scene); a
  // technique without one takes the largest.
  std::map<Technique, Margin> margins;
  // Per technique and map size (ShadowMapSettings::size) where it ran on enough cases: the
  // median as well. Raster time grows faster than the texel count, the more so the larger the
  // map and the stronger the warp (measured over typical time in data/calibration.csv, median:
  // LiSPSM 1.12 at 512, 1.96 at 4096), so one factor per technique over-priced small maps and
  // under-priced large ones.
  struct SizedMargin {
    double median = 1, p90 = 1;
    uint64_t cases = 0;
  };
  static constexpr uint64_t kMinSizedCases = 5;
  std::map<std::pair<Technique, uint32_t>, SizedMargin> sized;

  double margin(Technique technique) const;
  // What a candidate's time at the typical rates is multiplied by: for its typical time (the
  // median at its size, else 1) and its 90th percentile (at its size, else its technique's).
  std::pair<double, double> factors(Technique technique, uint32_t map_size) const;
};

class Calibration {
 public:
  static constexpr uint64_t kMinBinPixels = 10000;  // ~4% of one 640 x 360 view

  using Table = std::map<Technique, std::vector<CalibrationBin>>;

  // Throws std::invalid_argument naming `source`, the line and what is wrong.
  static Calibration parse(std::string_view text, const std::string& source);
  // The file at `path` (at most 1 MiB), parsed; throws std::invalid_argument naming it.
  static Calibration load(const std::string& path);
  // The table built into the server (data/calibration.csv at build time).
  static const Calibration& built_in();

  // The predicted misclassified pixels per boundary pixel of `technique` at a footprint: NaN (a
  // ray off every map) is 0, nothing there can be shadowed; a technique without bins throws
  // std::out_of_range. A bin measured on fewer than kMinBinPixels takes the rate of the next
  // coarser bin that was not (else, for PSM_CUBE, PSM's there; else of the nearest finer one).
  // Predictions never fall as the footprint grows (a finer map is never predicted worse): the
  // rates are pooled where they do, adjacent bins averaged by their pixels.
  double per_boundary_at(Technique technique, double footprint_px) const;
  bool has(Technique technique) const { return table_.count(technique) != 0; }
  const DeviceTimes& times() const { return times_; }
  // What a goal's candidate's error predicted from the bins is multiplied by: its technique and
  // map size's error margin where measured on at least kMinMarginViews views, else 1.
  static constexpr uint64_t kMinMarginViews = 5;
  double error_margin(Technique technique, uint32_t map_size) const;
  const ErrorMargins& error_margins() const { return errors_; }
  // A candidate's predicted device time: its cost at the typical rates with its maps' raster
  // `loads` (estimate_cost), times its technique's margin (the first light's, resolved) for the
  // 90th percentile.
  PredictedTime predict_time(const RenderRequest& request, const Plan& plan,
                             const MapLoads& loads = {}) const;
  std::string to_csv(const std::string& comment) const;
  const Table& table() const { return table_; }

  Calibration(Table table, DeviceTimes times, ErrorMargins errors = {});

 private:
  Table table_;     // as measured
  Table monotone_;  // what per_boundary_at reads
  ErrorMargins errors_;
  DeviceTimes times_;
};

}  // namespace shadow
