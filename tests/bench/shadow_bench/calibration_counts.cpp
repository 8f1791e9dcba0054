#include "calibration_counts.hpp"

#include <cmath>

namespace shadow::bench {

void CalibrationCounts::add_error(Technique t, const std::vector<float>& footprint,
                                  const std::vector<float>& vis, const std::vector<float>& ref,
                                  const std::vector<uint8_t>& faces_light,
                                  const std::vector<float>& boundary_share) {
  Counts& c = of_[t];
  for (size_t i = 0; i < vis.size(); ++i) {
    if (std::isnan(vis[i]) || std::isnan(ref[i]) || !(footprint[i] >= 0) || !faces_light[i])
      continue;
    size_t b = 0;
    while (footprint[i] > kEdges[b]) ++b;  // the last edge is inf
    ++c.pixels[b];
    c.wrong[b] += std::abs(vis[i] - ref[i]) > 0.5f;
    c.boundary[b] += boundary_share[i];
  }
}

void CalibrationCounts::add_time(const RenderRequest& request, const MapLoads& loads,
                                 const std::map<std::string, double>& passes, double device_ms) {
  const CostEstimate estimate =
      estimate_cost(request, make_plan(request), admission_rates(), loads);
  for (const StepCost& s : estimate.steps) {
    StepTime t{s.units, 0.0};
    for (const auto& [pass, ms] : passes)
      if (pass == s.step || pass.starts_with(s.step + ".")) t.ms += ms;
    steps_.push_back(t);
  }
  cases_.push_back(
      {estimate.steps, device_ms, request.shadow_map.technique, request.shadow_map.size});
}

void CalibrationCounts::add_measured(const std::string& view, Technique t, uint32_t map_size,
                                     double misclassified) {
  measured_[{view, {t, map_size}}] = misclassified;
}

void CalibrationCounts::add_predicted(const std::string& view,
                                      const std::vector<QualityCandidate>& candidates) {
  for (const QualityCandidate& c : candidates)
    predicted_[{view, {c.technique, c.size}}] = c.predicted_error;
}

Calibration CalibrationCounts::table() const {
  Calibration::Table table;
  for (const auto& [t, c] : of_)
    for (size_t b = 0; b < std::size(kEdges); ++b)
      table[t].push_back(
          {kEdges[b], c.boundary[b] > 0 ? double(c.wrong[b]) / c.boundary[b] : 0.0, c.pixels[b]});
  const RateFit fit = fit_rates(steps_, admission_rates());
  using Pairs = std::pair<std::vector<double>, std::vector<double>>;  // predicted, measured
  std::map<Technique, Pairs> of;
  std::map<std::pair<Technique, uint32_t>, Pairs> of_size;
  for (const TimedCase& c : cases_) {
    double ns = 0;
    for (const StepCost& s : c.steps)
      for (size_t r = 0; r < kCostRates; ++r) ns += s.units[r] * fit.rates.ns[r];
    for (Pairs* t : {&of[c.technique], &of_size[{c.technique, c.map_size}]}) {
      t->first.push_back(ns * 1e-6);
      t->second.push_back(c.device_ms);
    }
  }
  DeviceTimes times{fit.rates, fit.steps, {}, {}};
  for (const auto& [t, m] : of)
    times.margins[t] = {margin_quantile(m.first, m.second, kMarginQuantile), m.first.size()};
  for (const auto& [key, m] : of_size)
    times.sized[key] = {margin_quantile(m.first, m.second, 0.5),
                        margin_quantile(m.first, m.second, kMarginQuantile), m.first.size()};
  std::map<Configuration, Pairs> errors;
  for (const auto& [key, predicted] : predicted_)
    if (const auto m = measured_.find(key); m != measured_.end()) {
      errors[key.second].first.push_back(predicted);
      errors[key.second].second.push_back(m->second);
    }
  ErrorMargins margins;
  for (const auto& [key, e] : errors)
    margins[key] = {margin_quantile(e.first, e.second, kErrorQuantile), e.first.size()};
  return Calibration(std::move(table), times, std::move(margins));
}

}  // namespace shadow::bench
