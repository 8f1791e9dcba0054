#include "engine/passes/virtual_pages.hpp"

#include <cmath>
#include <numeric>
#include <stdexcept>

#include "engine/passes/pixel_shape.hpp"

namespace shadow {

cl_kernel VirtualPagesPass::mark_kernel() {
  return kernels_.kernel("virtual_pages.cl", "virtual_mark", pixel_shape(runtime_, kChunk).options);
}

cl_kernel VirtualPagesPass::allocate_kernel() {
  return kernels_.kernel("virtual_pages.cl", "virtual_allocate",
                         pixel_shape(runtime_, kChunk).options);
}

void VirtualPagesPass::warm_up() {
  mark_kernel();
}

void VirtualPagesPass::begin(uint32_t pool_pages) {
  pool_pages_ = pool_pages;
  runtime_.ensure(pool_, size_t{pool_pages} * kPageBytes);
  runtime_.ensure(slot_page_, size_t{pool_pages} * sizeof(uint32_t));
  runtime_.ensure(counter_, kCounterWords * sizeof(uint32_t));
  kept_[0] = kept_[1] = 0;
}

VirtualMap& VirtualPagesPass::mark(uint32_t light, const GBuffer& view, uint32_t width,
                                   uint32_t pixels, const Camera& camera,
                                   const DirectionalClipmap& clipmap, double bias, float reach,
                                   Timeline& timeline, float coarsen_beyond) {
  if (light >= maps_.size()) maps_.resize(light + 1), level_ndc_.resize(light + 1);
  VirtualMap& map = maps_[light];
  map.clipmap = clipmap;
  const size_t levels = clipmap.levels.size();
  runtime_.ensure(map.marks, map.page_count());
  timeline.add("virtual.mark", runtime_.fill_zero(map.marks));
  first_page_table_.clear();
  std::vector<glm::mat4>& ndc = level_ndc_[light];
  ndc.clear();
  for (const ClipmapLevel& l : clipmap.levels) {
    first_page_table_.emplace_back(l.first_page);
    ndc.emplace_back(l.setup.world_to_ndc);
  }
  runtime_.ensure(first_pages_, levels * sizeof(glm::vec2));
  timeline.add("virtual.mark",
               runtime_.write(first_pages_, first_page_table_.data(), levels * sizeof(glm::vec2)));
  runtime_.ensure(map.level_ndc, levels * sizeof(glm::mat4));
  timeline.add("virtual.mark",
               runtime_.write(map.level_ndc, ndc.data(), levels * sizeof(glm::mat4)));
  runtime_.ensure(map.pixel_level, std::max<size_t>(pixels, 1));
  const PixelShape shape = pixel_shape(runtime_, kChunk);
  work_items_ = shape.work_items(pixels);
  runtime_.ensure(outside_, std::max<size_t>(work_items_, 1) * 2 * sizeof(uint32_t));
  const glm::dmat4& v = clipmap.view;  // rows x and y: world -> light-space u, v
  const glm::vec4 u(v[0][0], v[1][0], v[2][0], v[3][0]), w(v[0][1], v[1][1], v[2][1], v[3][1]);
  const float pixel_angle =
      float(2.0 * std::tan(glm::radians(0.5 * double(camera.fov_deg))) / camera.height);
  cl_kernel k = mark_kernel();
  cl::set_args(k, view.position, width, pixels, glm::vec4(camera.eye, 1.0f), pixel_angle, u, w,
               int32_t(clipmap.levels.front().level), uint32_t(levels), first_pages_,
               clipmap.texels, float(std::exp2(bias)), reach, coarsen_beyond, map.marks, outside_,
               map.pixel_level);
  timeline.add("virtual.mark", runtime_.launch(k, work_items_, shape.group));
  return map;
}

void VirtualPagesPass::allocate(VirtualMap& map, Timeline& timeline) {
  runtime_.ensure(map.table, map.page_count() * sizeof(uint32_t));
  cl_kernel k = allocate_kernel();
  const uint32_t levels = uint32_t(map.clipmap.levels.size());
  if (levels > kMaxLevels) throw std::logic_error("VirtualPagesPass: too many levels");
  timeline.add("virtual.allocate", runtime_.write(counter_, kept_, sizeof kept_));
  cl::set_args(k, map.marks, levels, map.pages(), pool_pages_, counter_, map.table, slot_page_);
  timeline.add("virtual.allocate", runtime_.launch(k, 1));
  levels_ = levels;
  allocated_ = &map;
}

VirtualPagesPass::Counts VirtualPagesPass::counts() {
  uint32_t c[kCounterWords] = {};
  runtime_.read(counter_, c, sizeof c);
  runtime_.finish();
  last_ = {c[1], c[0]};
  if (allocated_) {
    allocated_->level_slots.assign(c + 2, c + 2 + levels_);
    allocated_->first_slot.clear();
    allocated_->page_box.clear();
    for (uint32_t l = 0, first = kept_[0]; l < levels_; first += c[2 + l++]) {
      allocated_->first_slot.push_back(first);
      const uint32_t* box = c + 2 + kMaxLevels + 4 * l;
      allocated_->page_box.emplace_back(box[0], box[1], box[2], box[3]);
    }
  }
  return last_;
}

PageTarget VirtualPagesPass::target(const VirtualMap& map, uint32_t level) const {
  const glm::ivec4 box = map.page_box.at(level);  // pages -> tiles, inclusive
  constexpr int per_page = int(kPageTexels / Rasterizer::kTile);
  return {&map.table,
          level * map.pages() * map.pages(),
          &pool_,
          &slot_page_,
          map.first_slot.at(level),
          map.level_slots.at(level),
          {box.x * per_page, box.y * per_page, box.z * per_page + per_page - 1,
           box.w * per_page + per_page - 1}};
}

void VirtualPagesPass::keep() {
  kept_[0] = uint32_t(last_.resident), kept_[1] = uint32_t(last_.requested);
}

VirtualPagesPass::PixelCounts VirtualPagesPass::pixel_counts() {
  std::vector<uint32_t> per_item(2 * work_items_);
  if (!per_item.empty()) {
    runtime_.read(outside_, per_item.data(), per_item.size() * sizeof(uint32_t));
    runtime_.finish();
  }
  PixelCounts out;
  for (size_t i = 0; i < work_items_; ++i)
    out.outside += per_item[2 * i], out.coarsened += per_item[2 * i + 1];
  return out;
}

}  // namespace shadow
