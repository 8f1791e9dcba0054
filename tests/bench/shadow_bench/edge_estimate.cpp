#include "edge_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

namespace shadow::bench {

std::string technique_of(const std::string& variant) {
  return variant.substr(0, variant.find(' '));
}

void write_edge_estimate_section(const std::vector<Case>& cases, std::ostream& md) {
  struct Spread {
    int n = 0;
    double sum = 0, sum_sq = 0;
  };
  std::map<std::string, Spread> by_technique;
  std::vector<const Case*> unexplained;
  for (const Case& c : cases) {
    if (!c.edge_estimate) continue;
    const double measured = c.error.misclassified_rate(), estimate = *c.edge_estimate;
    if (measured > kUnexplainedFactor * estimate) unexplained.push_back(&c);
    if (!(measured > 0 && estimate > 0)) continue;
    const double r = std::log(estimate / measured);
    for (const std::string& key : {technique_of(c.variant), std::string("all")}) {
      Spread& s = by_technique[key];
      ++s.n, s.sum += r, s.sum_sq += r * r;
    }
  }
  if (by_technique.empty() && unexplained.empty()) return;
  md << "\n## Edge sampling against the measured error\n\n"
        "Each hard-test variant (a fixed technique, no goal) rendered once more with the bilinear "
        "2x2 filter: the mean |hard - bilinear| over the seen pixels is the misclassified rate "
        "edge sampling alone explains (a shadow edge between two texel centres lies anywhere "
        "between them; oracle::edge_sampling_estimate). It needs no reference. log(estimate / "
        "measured) per technique (0: the estimate is the error; -0.69: half of it):\n\n"
        "| technique | cases | mean | spread (sd) |\n|---|---:|---:|---:|\n";
  char line[512];
  for (const auto& [t, s] : by_technique) {
    const double mean = s.sum / s.n;
    std::snprintf(line, sizeof line, "| %s | %d | %+.2f | %.2f |\n", t.c_str(), s.n, mean,
                  std::sqrt(std::max(0.0, s.sum_sq / s.n - mean * mean)));
    md << line;
  }
  std::snprintf(
      line, sizeof line,
      "\nMeasured above %.0fx the estimate (%zu cases): most of the error there is not "
      "an edge between texels: bias, receivers grazed by the light, occluders thinner than "
      "a texel (which both tests miss) or casters missing from a map.\n\n",
      kUnexplainedFactor, unexplained.size());
  md << line << "| scene | view | variant | measured | estimate |\n|---|---|---|---:|---:|\n";
  for (const Case* c : unexplained) {
    std::snprintf(line, sizeof line, "| %s | %s | %s | %.3f%% | %.3f%% |\n", c->scene.c_str(),
                  c->view.c_str(), c->variant.c_str(), 100 * c->error.misclassified_rate(),
                  100 * *c->edge_estimate);
    md << line;
  }
}

}  // namespace shadow::bench
