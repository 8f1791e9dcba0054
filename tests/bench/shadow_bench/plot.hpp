// A time-vs-error scatter plot as a PNG, with the Pareto front marked (no fonts needed).
#pragma once

#include <filesystem>
#include <vector>

namespace shadow::bench {

struct PlotPoint {
  double time_ms;  // x, log scale
  double error;    // y, linear from 0
  bool pareto;
};

// Indices of the points no other point beats on both time and error (ties kept).
std::vector<bool> pareto_front(const std::vector<double>& time, const std::vector<double>& error);

// Grey dots for dominated points, red squares joined by a red line for the front; light grid
// lines at each power of ten in x and each tenth of the error range in y.
void write_plot(const std::vector<PlotPoint>& points, const std::filesystem::path& file);

}  // namespace shadow::bench
