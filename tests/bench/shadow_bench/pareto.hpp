// The Pareto front of shadow-bench's variants: time against error.
#pragma once

#include <vector>

namespace shadow::bench {

// Indices of the points no other point beats on both time and error (ties kept).
std::vector<bool> pareto_front(const std::vector<double>& time, const std::vector<double>& error);

}  // namespace shadow::bench
