#include "engine/passes/boundary.hpp"

#include <vector>

namespace shadow {

double BoundaryPass::run(const cl::Buffer& visibility, uint32_t width, uint32_t height,
                         Timeline& timeline) {
  runtime_.ensure(partials_, size_t{height} * 2 * sizeof(uint32_t));
  cl_kernel k = kernels_.kernel("reduce.cl", "boundary_partials");
  cl::set_args(k, visibility, width, height, partials_);
  timeline.add("boundary.count", runtime_.launch(k, height));
  std::vector<uint32_t> partials(size_t{height} * 2);
  timeline.add("boundary.count",
               runtime_.read(partials_, partials.data(), partials.size() * sizeof(uint32_t)));
  uint64_t seen = 0, boundary = 0;
  for (uint32_t y = 0; y < height; ++y) {
    seen += partials[2 * y];
    boundary += partials[2 * y + 1];
  }
  return seen ? double(boundary) / double(seen) : 0.0;
}

}  // namespace shadow
