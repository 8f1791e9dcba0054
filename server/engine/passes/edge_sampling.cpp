#include "engine/passes/edge_sampling.hpp"

#include <vector>

namespace shadow {

double EdgeSamplingPass::run(const cl::Buffer& hard, const cl::Buffer& filtered, uint32_t width,
                             uint32_t height, Timeline& timeline) {
  runtime_.ensure(partials_, size_t{height} * 2 * sizeof(float));
  cl_kernel k = kernels_.kernel("reduce.cl", "edge_sampling_partials");
  cl::set_args(k, hard, filtered, width, height, partials_);
  timeline.add("edge_sampling", runtime_.launch(k, height));
  std::vector<float> partials(size_t{height} * 2);
  timeline.add("edge_sampling",
               runtime_.read(partials_, partials.data(), partials.size() * sizeof(float)));
  double seen = 0, sum = 0;
  for (uint32_t y = 0; y < height; ++y) {
    seen += partials[2 * y];
    sum += partials[2 * y + 1];
  }
  return seen > 0 ? sum / seen : 0.0;
}

}  // namespace shadow
