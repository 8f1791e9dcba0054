#include "engine/passes/depth_range.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace shadow {

std::optional<DepthRange> DepthRangePass::run(const GBuffer& g, Timeline& timeline) {
  if (g.chunks == 0) return std::nullopt;  // a view no resolve wrote (or of no pixel)
  std::vector<float> partials(size_t{g.chunks} * 2);
  timeline.add("depth_range.reduce",
               runtime_.read(g.depth_partials, partials.data(), partials.size() * sizeof(float)));
  DepthRange r{INFINITY, -INFINITY};
  for (uint32_t c = 0; c < g.chunks; ++c) {
    r.min = std::min(r.min, double(partials[2 * c]));
    r.max = std::max(r.max, double(partials[2 * c + 1]));
  }
  if (!(r.min <= r.max)) return std::nullopt;
  return r;
}

}  // namespace shadow
