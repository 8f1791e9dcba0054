#include "engine/passes/boundary.hpp"

#include "engine/auto_pick.hpp"  // kSampleColumns, kSampleRows

namespace shadow {

BoundaryCount BoundaryPass::run(const cl::Buffer& visibility, uint32_t width, uint32_t height,
                                Timeline& timeline) {
  constexpr uint32_t kCells = kSampleColumns * kSampleRows;
  runtime_.ensure(cells_, kCells * 2 * sizeof(uint32_t));
  cl_kernel k = kernels_.kernel("reduce.cl", "boundary_cells");
  cl::set_args(k, visibility, width, height, kSampleColumns, kSampleRows, cells_);
  timeline.add("boundary.count", runtime_.launch(k, kCells));
  std::vector<uint32_t> counts(kCells * 2);  // seen, boundary
  timeline.add("boundary.count",
               runtime_.read(cells_, counts.data(), counts.size() * sizeof(uint32_t)));
  BoundaryCount out;
  uint64_t seen = 0, boundary = 0;
  for (uint32_t i = 0; i < kCells; ++i) {
    seen += counts[2 * i];
    boundary += counts[2 * i + 1];
    out.cells.push_back(counts[2 * i + 1]);
  }
  out.share = seen ? double(boundary) / double(seen) : 0.0;
  return out;
}

}  // namespace shadow
