#include "case.hpp"

#include <algorithm>

namespace shadow::bench {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

void TimedRuns::add(double wall_ms, const std::vector<PassTiming>& timings) {
  wall.push_back(wall_ms);
  std::map<std::string, double> sum;  // a pass may run more than once per request
  for (const PassTiming& t : timings) sum[t.pass] += t.device_ms;
  for (const auto& [pass, ms] : sum) passes[pass].push_back(ms);
}

void TimedRuns::summarize(Case& c) const {
  c.wall_median = median(wall);
  c.wall_min = wall.empty() ? 0.0 : *std::min_element(wall.begin(), wall.end());
  c.wall_max = wall.empty() ? 0.0 : *std::max_element(wall.begin(), wall.end());
  c.device_ms = 0;
  for (const auto& [pass, v] : passes) {
    c.passes[pass] = median(v);
    c.device_ms += c.passes[pass];
  }
}

void set_map_report(Case& c, const LightFitReport& fit, uint32_t map_size) {
  c.light_case = fit.light_case;
  c.map_faces = 1;
  if (!fit.cube_faces.empty()) {
    c.map_faces = uint32_t(std::count_if(fit.cube_faces.begin(), fit.cube_faces.end(),
                                         [](const CubeFaceReport& f) { return f.rendered; }));
  }
  if (fit.auto_map_size) map_size = fit.auto_map_size;  // AUTO's PSM cube: its faces'
  c.map_texels = uint64_t{c.map_faces} * map_size * map_size;
  c.cube_texel_min = fit.cube_texel_min;
  c.cube_texel_max = fit.cube_texel_max;
}

}  // namespace shadow::bench
