// shadow-bench's "edge sampling" section: each hard-test variant's misclassified rate against
// the estimate of edge sampling alone (Case::edge_estimate). Where the measured error is well
// above the estimate, most of it is not an edge between texels: bias, grazing receivers,
// occluders thinner than a texel (both tests miss them), casters missing from a map, or the
// reference itself.
#pragma once

#include <ostream>
#include <vector>

#include "case.hpp"

namespace shadow::bench {

// Measured beyond this many times the estimate, a case is listed as not explained by sampling.
inline constexpr double kUnexplainedFactor = 2.0;

// The technique a variant's name starts with ("lispsm 2048 slope 4" -> "lispsm").
std::string technique_of(const std::string& variant);

// Writes the section: per technique, the mean and spread of log(estimate / measured) over the
// cases with both above zero; then the cases measured above kUnexplainedFactor x the estimate.
// Nothing when no case has an estimate.
void write_edge_estimate_section(const std::vector<Case>& cases, std::ostream& md);

}  // namespace shadow::bench
