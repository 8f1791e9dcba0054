// shadow-bench's ceiling of the error goals (issue 17): how many views a max_error goal would
// meet within 1.5x the cost of the cheapest fixed configuration that met it, had each candidate's
// error been predicted to within a given spread; read against the spreads of the server's
// prediction, of the edge-sampling estimate, and of the measured rate itself over nudged frames.
// It says how good an error prediction the goal needs, and what the probe's own measures cost
// the goal whatever the prediction.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "case.hpp"
#include "frames.hpp"

namespace shadow::bench {

// One max_error goal replayed at one spread.
struct CeilingPoint {
  std::string goal;      // its variant, "quality error 1.0%"
  double sigma = 0;      // the predictions' spread: sd of log(predicted / measured)
  bool measures = true;  // false: the probe's measures cost nothing (goal_cost_ms)
  double within = 0;     // views met within 1.5x, mean over the draws
  int views = 0;         // views where a fixed configuration met the bound
};

// Each max_error goal among `cases` replayed `draws` times at each of `sigmas`, with the probe's
// measures costing what they cost and costing nothing. A draw predicts each candidate's error as
// its fixed run's measured rate times exp(sigma z), z standard normal, one per view and
// configuration (the goals at each bound share a view's prediction, as the server's do), times
// the margin the calibration would set (margin_quantile at kErrorQuantile over the views, per
// configuration). The pick is the candidate predicted to meet the bound at the least cost the
// goal would have had picking it (goal_cost_ms of as_picked): times known, so that only the
// error prediction varies; predicted to meet none, the least predicted. Candidates without a
// fixed run are left out. The same `seed`, the same figures.
std::vector<CeilingPoint> goal_ceiling(const std::vector<Case>& cases,
                                       const std::vector<double>& sigmas, int draws, uint64_t seed);

// Spreads, sd of log(estimate / measured) over the cases with both above 0.
struct Spreads {
  double prediction = 0;  // the goals' candidates' predicted errors against their fixed runs
  size_t predictions = 0;
  double edge_estimate = 0;  // fixed runs' edge-sampling estimates (edge_estimate.hpp)
  size_t estimates = 0;
  // Per fixed run with nudged frames, the sd of log(rate) over the view and those frames: the
  // median and mean over the runs. No prediction that does not draw the frame gets below it.
  double frames_median = 0, frames_mean = 0;
  size_t frame_runs = 0;
};
Spreads prediction_spreads(const std::vector<Case>& cases, const std::vector<FrameError>& frames);

// Writes the section to `md` (nothing without max_error goals) and the figures goal_ceiling.png
// is drawn from (scripts/plot_bench.py) to `csv`: rows kind,name,sigma,measures,within,views of
// kind "curve" (goal_ceiling), "spread" (prediction_spreads) and "actual" (each goal's views
// within 1.5x as it ran, at the prediction's spread).
void write_goal_ceiling(const std::vector<Case>& cases, const std::vector<FrameError>& frames,
                        std::ostream& md, std::ostream& csv);

}  // namespace shadow::bench
