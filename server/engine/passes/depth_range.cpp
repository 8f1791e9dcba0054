#include "engine/passes/depth_range.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace shadow {

std::optional<DepthRange> DepthRangePass::run(const GBuffer& g, const Camera& camera,
                                              Timeline& timeline) {
  const uint32_t pixels = camera.width * camera.height;
  const uint32_t chunks = (pixels + kChunk - 1) / kChunk;
  runtime_.ensure(partials_, size_t{chunks} * 2 * sizeof(float));
  // The forward axis in double, rounded once.
  const glm::dvec3 eye(camera.eye), fwd = glm::normalize(glm::dvec3(camera.target) - eye);
  const glm::vec4 eye4(glm::vec3(eye), 1.0f), fwd4(glm::vec3(fwd), 0.0f);
  cl_kernel k = kernels_.kernel("reduce.cl", "view_depth_partials");
  cl::set_args(k, g.position, g.normal, pixels, eye4, fwd4, partials_);
  timeline.add("depth_range.reduce", runtime_.launch(k, chunks));
  std::vector<float> partials(size_t{chunks} * 2);
  timeline.add("depth_range.reduce",
               runtime_.read(partials_, partials.data(), partials.size() * sizeof(float)));
  DepthRange r{INFINITY, -INFINITY};
  for (uint32_t c = 0; c < chunks; ++c) {
    r.min = std::min(r.min, double(partials[2 * c]));
    r.max = std::max(r.max, double(partials[2 * c + 1]));
  }
  if (!(r.min <= r.max)) return std::nullopt;
  return r;
}

}  // namespace shadow
