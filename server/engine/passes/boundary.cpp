#include "engine/passes/boundary.hpp"

#include <cmath>

#include "engine/choose/auto_pick.hpp"  // kSampleColumns, kSampleRows
#include "engine/passes/light_args.hpp"
#include "engine/passes/pixel_shape.hpp"

namespace shadow {

cl_kernel BoundaryPass::kernel() {
  const size_t group = chunk_group(runtime_);
  if (group == 1) return kernels_.kernel("boundary.cl", "boundary_cells");
  return kernels_.kernel("boundary.cl", "boundary_cells_gpu", group_option(group));
}

BoundaryCount BoundaryPass::run(const cl::Buffer& visibility, const GBuffer& view,
                                const Camera& camera, const Light& light, Timeline& timeline) {
  constexpr uint32_t kCells = kSampleColumns * kSampleRows;
  runtime_.ensure(cells_, kCells * 2 * sizeof(uint32_t));
  // A pixel's extent per unit distance, on the image plane.
  const double pixel = 2 * std::tan(glm::radians(0.5 * double(camera.fov_deg))) / camera.height;
  const glm::vec4 eye(camera.eye, float(pixel));
  cl_kernel k = kernel();
  cl::set_args(k, visibility, view.position, view.normal, camera.width, camera.height,
               kSampleColumns, kSampleRows, eye, light_item(light), cells_);
  timeline.add("boundary.count",
               runtime_.launch(k, kCells * chunk_group(runtime_), chunk_group(runtime_)));
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
