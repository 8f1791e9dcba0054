#include "engine/passes/virtual_pages.hpp"

#include <cmath>
#include <numeric>

#include "engine/passes/pixel_shape.hpp"

namespace shadow {

cl_kernel VirtualPagesPass::kernel() {
  return kernels_.kernel("virtual_pages.cl", "virtual_mark", pixel_shape(runtime_, kChunk).options);
}

void VirtualPagesPass::warm_up() {
  kernel();
}

const cl::Buffer& VirtualPagesPass::mark(const GBuffer& view, uint32_t width, uint32_t pixels,
                                         const Camera& camera, const DirectionalClipmap& clipmap,
                                         double bias, uint32_t reach, Timeline& timeline) {
  const uint32_t pages = clipmap.texels / kPageTexels;
  const size_t table = size_t{pages} * pages, levels = clipmap.levels.size();
  runtime_.ensure(marks_, levels * table);
  timeline.add("virtual.mark", runtime_.fill_zero(marks_));
  first_page_table_.clear();
  for (const ClipmapLevel& l : clipmap.levels) first_page_table_.emplace_back(l.first_page);
  runtime_.ensure(first_pages_, levels * sizeof(glm::vec2));
  timeline.add("virtual.mark",
               runtime_.write(first_pages_, first_page_table_.data(), levels * sizeof(glm::vec2)));
  const PixelShape shape = pixel_shape(runtime_, kChunk);
  work_items_ = shape.work_items(pixels);
  runtime_.ensure(outside_, std::max<size_t>(work_items_, 1) * sizeof(uint32_t));
  const glm::dmat4& v = clipmap.view;  // rows x and y: world -> light-space u, v
  const glm::vec4 u(v[0][0], v[1][0], v[2][0], v[3][0]), w(v[0][1], v[1][1], v[2][1], v[3][1]);
  const float pixel_angle =
      float(2.0 * std::tan(glm::radians(0.5 * double(camera.fov_deg))) / camera.height);
  cl_kernel k = kernel();
  cl::set_args(k, view.position, width, pixels, glm::vec4(camera.eye, 1.0f), pixel_angle, u, w,
               int32_t(clipmap.levels.front().level), uint32_t(levels), first_pages_,
               clipmap.texels, float(std::exp2(bias)), float(reach), marks_, outside_);
  timeline.add("virtual.mark", runtime_.launch(k, work_items_, shape.group));
  return marks_;
}

uint64_t VirtualPagesPass::outside() {
  std::vector<uint32_t> per_item(work_items_);
  if (!per_item.empty()) {
    runtime_.read(outside_, per_item.data(), per_item.size() * sizeof(uint32_t));
    runtime_.finish();
  }
  return std::accumulate(per_item.begin(), per_item.end(), uint64_t{0});
}

}  // namespace shadow
