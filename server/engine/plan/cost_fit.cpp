#include "engine/plan/cost_fit.hpp"

#include <algorithm>
#include <cmath>

namespace shadow {

RateFit fit_rates(const std::vector<StepTime>& steps, const CostRates& fallback) {
  RateFit fit{fallback, {}};
  std::vector<const StepTime*> used;
  for (const StepTime& s : steps)
    if (s.ms > 0 && std::isfinite(s.ms)) used.push_back(&s);
  std::vector<size_t> free;  // the rates being fitted
  for (size_t r = 0; r < kCostRates; ++r) {
    for (const StepTime* s : used) fit.steps[r] += s->units[r] > 0;
    if (fit.steps[r]) free.push_back(r);
  }
  while (!free.empty()) {
    const size_t n = free.size();
    // Rows units / ms against 1 (relative error), each column scaled to unit length so one
    // pivot threshold suits rates of every magnitude.
    std::vector<double> scale(n, 0.0);
    for (const StepTime* s : used)
      for (size_t j = 0; j < n; ++j) scale[j] += std::pow(s->units[free[j]] / s->ms, 2);
    for (double& c : scale) c = std::sqrt(c);
    std::vector<std::vector<double>> m(n, std::vector<double>(n + 1, 0.0));  // [A^T A | A^T 1]
    for (const StepTime* s : used)
      for (size_t i = 0; i < n; ++i) {
        const double ai = s->units[free[i]] / s->ms / scale[i];
        for (size_t j = 0; j < n; ++j) m[i][j] += ai * s->units[free[j]] / s->ms / scale[j];
        m[i][n] += ai;
      }
    // Gaussian elimination with partial pivoting; a vanishing pivot marks a column the steps
    // cannot tell from the ones before it.
    std::vector<size_t> order(n);
    for (size_t i = 0; i < n; ++i) order[i] = i;
    size_t degenerate = n;
    for (size_t k = 0; k < n && degenerate == n; ++k) {
      size_t p = k;
      for (size_t i = k + 1; i < n; ++i)
        if (std::abs(m[i][k]) > std::abs(m[p][k])) p = i;
      if (std::abs(m[p][k]) < 1e-10) {
        degenerate = k;
        break;
      }
      std::swap(m[p], m[k]);
      for (size_t i = k + 1; i < n; ++i) {
        const double f = m[i][k] / m[k][k];
        for (size_t j = k; j <= n; ++j) m[i][j] -= f * m[k][j];
      }
    }
    if (degenerate != n) {
      fit.rates.ns[free[degenerate]] = fallback.ns[free[degenerate]];
      fit.steps[free[degenerate]] = 0;
      free.erase(free.begin() + std::ptrdiff_t(degenerate));
      continue;
    }
    std::vector<double> x(n);
    for (size_t k = n; k-- > 0;) {
      double v = m[k][n];
      for (size_t j = k + 1; j < n; ++j) v -= m[k][j] * x[j];
      x[k] = v / m[k][k];
    }
    const auto lowest = std::min_element(x.begin(), x.end());
    if (*lowest < 0) {  // the most negative is 0, the rest fitted again without it
      const size_t j = size_t(lowest - x.begin());
      fit.rates.ns[free[j]] = 0;
      free.erase(free.begin() + std::ptrdiff_t(j));
      continue;
    }
    for (size_t j = 0; j < n; ++j) fit.rates.ns[free[j]] = x[j] / scale[j] * 1e6;  // ms to ns
    break;
  }
  return fit;
}

double margin_quantile(const std::vector<double>& predicted, const std::vector<double>& measured,
                       double quantile) {
  std::vector<double> ratios;
  for (size_t i = 0; i < predicted.size() && i < measured.size(); ++i)
    if (predicted[i] > 0 && std::isfinite(predicted[i]) && measured[i] >= 0 &&
        std::isfinite(measured[i]))
      ratios.push_back(measured[i] / predicted[i]);
  if (ratios.empty()) return 1.0;
  std::sort(ratios.begin(), ratios.end());
  const double rank = std::ceil(std::clamp(quantile, 0.0, 1.0) * double(ratios.size()));
  return ratios[size_t(std::max(rank, 1.0)) - 1];
}

}  // namespace shadow
