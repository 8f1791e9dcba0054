// Typical device-time rates (engine/plan/cost.hpp) fitted to measured steps: what a quality goal
// predicts a candidate's time with, where admission's rates err high on purpose.
// shadow-bench --calibration fits them to the passes of its cases; tested on synthetic steps.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "engine/plan/cost.hpp"

namespace shadow {

// A step as estimate_cost prices it (its units of each rate) and its measured device time.
struct StepTime {
  std::array<double, kCostRates> units{};
  double ms = 0;
};

struct RateFit {
  CostRates rates;
  std::array<uint64_t, kCostRates> steps{};  // the steps each rate was fitted on (0: `fallback`'s)
};

// Least squares on the relative error of each step's predicted time, over the rates some step
// has units of; the others keep `fallback`'s. A rate that would come out negative is 0, and one
// the steps cannot tell apart from others (always in the same proportion) keeps `fallback`'s.
// Steps measured at 0 ms (did not run) are skipped.
RateFit fit_rates(const std::vector<StepTime>& steps, const CostRates& fallback);

// The `quantile` (0..1) of measured / predicted over the cases predicted above 0 and measured at
// 0 or more: the margin that covers that share of them (device times, errors). 1 without cases.
double margin_quantile(const std::vector<double>& predicted, const std::vector<double>& measured,
                       double quantile);

}  // namespace shadow
