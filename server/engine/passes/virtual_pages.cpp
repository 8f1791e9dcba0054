#include "engine/passes/virtual_pages.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "engine/passes/light_args.hpp"
#include "engine/passes/pixel_shape.hpp"

namespace shadow {

cl_kernel VirtualPagesPass::kernel(const char* name) {
  return kernels_.kernel("virtual_pages.cl", name, pixel_shape(runtime_, kChunk).options);
}

void VirtualPagesPass::warm_up() {
  for (const char* k : {"virtual_mark", "virtual_count", "virtual_allocate", "virtual_invalidate",
                        "virtual_pool_image", "virtual_table_image", "virtual_level_image"})
    kernel(k);
}

void VirtualPagesPass::begin(uint32_t pool_pages, bool keeping, Timeline& timeline) {
  const bool fresh = !keeping || pool_pages != pool_pages_ || frame_ == 0;
  pool_pages_ = pool_pages;
  hash_mask_ = std::bit_ceil(2 * pool_pages) - 1;  // at most half full
  runtime_.ensure(pool_, size_t{pool_pages} * kPageBytes);
  runtime_.ensure(slot_owner_, size_t{pool_pages} * 8 * sizeof(uint32_t));  // page_key_t
  runtime_.ensure(slot_frame_, size_t{pool_pages} * sizeof(uint32_t));
  runtime_.ensure(slot_valid_, size_t{pool_pages} * sizeof(uint32_t));
  runtime_.ensure(hash_, (size_t{hash_mask_} + 1) * sizeof(uint32_t));
  runtime_.ensure(draw_list_, size_t{pool_pages} * 2 * sizeof(uint32_t));
  runtime_.ensure(counter_, kCounterWords * sizeof(uint32_t));
  runtime_.ensure(marked_, sizeof(uint32_t));
  timeline.add("virtual.mark", runtime_.fill_zero(counter_));
  if (fresh) {  // every slot unowned (a key of all ones), never marked, invalid
    frame_ = 0;
    timeline.add("virtual.mark", runtime_.fill(slot_owner_, 0xffffffffu));
    timeline.add("virtual.mark", runtime_.fill_zero(slot_frame_));
    timeline.add("virtual.mark", runtime_.fill_zero(slot_valid_));
  }
  ++frame_;
}

VirtualMap& VirtualPagesPass::mark(uint32_t light, const GBuffer& view, uint32_t width,
                                   uint32_t pixels, const Camera& camera,
                                   const VirtualLevels& layout, double bias, float reach,
                                   Timeline& timeline, float coarsen_beyond,
                                   const glm::vec4& soft) {
  if (light >= maps_.size()) maps_.resize(light + 1);
  VirtualMap& map = maps_[light];
  map.layout = layout;
  const size_t levels = layout.levels.size();
  runtime_.ensure(map.marks, map.page_count());
  timeline.add("virtual.mark", runtime_.fill_zero(map.marks));
  write_levels(light, map, "virtual.mark", timeline);
  runtime_.ensure(map.pixel_level, std::max<size_t>(pixels, 1));
  const PixelShape shape = pixel_shape(runtime_, kChunk);
  work_items_ = shape.work_items(pixels);
  runtime_.ensure(outside_, std::max<size_t>(work_items_, 1) * 2 * sizeof(uint32_t));
  // Light space: a directional light's view (rows u and v), or each perspective face's matrix.
  LevelTables& tables = level_tables_[light];
  tables.to_light.clear();
  if (layout.perspective())
    for (const glm::dmat4& f : layout.face_ndc) tables.to_light.emplace_back(f);
  else
    tables.to_light.emplace_back(layout.view);
  runtime_.ensure(to_light_, tables.to_light.size() * sizeof(glm::mat4));
  timeline.add("virtual.mark", runtime_.write(to_light_, tables.to_light.data(),
                                              tables.to_light.size() * sizeof(glm::mat4)));
  const float pixel_angle =
      float(2.0 * std::tan(glm::radians(0.5 * double(camera.fov_deg))) / camera.height);
  cl_kernel k = kernel("virtual_mark");
  cl::set_args(k, view.position, width, pixels, glm::vec4(camera.eye, 1.0f), pixel_angle, to_light_,
               uint32_t(layout.faces), faces_args(layout.cube),
               int32_t(layout.levels.front().level), uint32_t(levels), first_pages_, layout.texels,
               float(std::exp2(bias)), reach, soft, coarsen_beyond, map.marks, outside_,
               map.pixel_level);
  timeline.add("virtual.mark", runtime_.launch(k, work_items_, shape.group));
  return map;
}

uint64_t VirtualPagesPass::marked(const VirtualMap& map, Timeline& timeline) {
  cl_kernel k = kernel("virtual_count");
  cl::set_args(k, map.marks, uint32_t(map.page_count()), marked_);
  timeline.add("virtual.count", runtime_.launch(k, 1));
  uint32_t n = 0;
  runtime_.read(marked_, &n, sizeof n);
  runtime_.finish();
  return n;
}

void VirtualPagesPass::invalidate(uint32_t light, bool all, const std::vector<glm::vec4>& boxes,
                                  uint32_t texels, Timeline& timeline) {
  if (!all && boxes.empty()) return;
  box_table_ = boxes;
  if (box_table_.empty()) box_table_.emplace_back(0.0f);  // a buffer, never read
  runtime_.ensure(boxes_, box_table_.size() * sizeof(glm::vec4));
  timeline.add("virtual.allocate",
               runtime_.write(boxes_, box_table_.data(), box_table_.size() * sizeof(glm::vec4)));
  cl_kernel k = kernel("virtual_invalidate");
  cl::set_args(k, slot_owner_, pool_pages_, light, uint32_t(all), boxes_, uint32_t(boxes.size()),
               texels, slot_valid_);
  timeline.add("virtual.allocate", runtime_.launch(k, pool_pages_));
}

void VirtualPagesPass::write_levels(uint32_t light, VirtualMap& map, const char* pass,
                                    Timeline& timeline) {
  const size_t levels = map.layout.levels.size();
  if (levels > kMaxLevels) throw std::logic_error("VirtualPagesPass: too many levels");
  if (light >= level_tables_.size()) level_tables_.resize(light + 1);
  LevelTables& t = level_tables_[light];
  t.first_pages.clear(), t.ndc.clear();
  t.texels.clear();
  for (size_t i = 0; i < levels; ++i) {
    t.first_pages.emplace_back(map.layout.levels[i].first_page);
    t.ndc.emplace_back(map.layout.levels[i].setup.world_to_ndc);
    t.texels.push_back(map.layout.extent(i));
  }
  runtime_.ensure(first_pages_, levels * sizeof(glm::vec2));
  timeline.add(pass,
               runtime_.write(first_pages_, t.first_pages.data(), levels * sizeof(glm::vec2)));
  runtime_.ensure(map.level_ndc, levels * sizeof(glm::mat4));
  timeline.add(pass, runtime_.write(map.level_ndc, t.ndc.data(), levels * sizeof(glm::mat4)));
  runtime_.ensure(map.level_texels, levels * sizeof(uint32_t));
  timeline.add(pass, runtime_.write(map.level_texels, t.texels.data(), levels * sizeof(uint32_t)));
}

void VirtualPagesPass::allocate(uint32_t light, VirtualMap& map, Timeline& timeline) {
  // Its levels' first pages again: allocate() also serves maps marked elsewhere (tests).
  write_levels(light, map, "virtual.allocate", timeline);
  runtime_.ensure(map.table, map.page_count() * sizeof(uint32_t));
  runtime_.ensure(map.draw_table, map.page_count() * sizeof(uint32_t));
  cl_kernel k = kernel("virtual_allocate");
  cl::set_args(k, map.marks, uint32_t(map.layout.levels.size()), map.pages(),
               uint32_t(map.layout.mips), int32_t(map.layout.levels.front().level), first_pages_,
               light, frame_, pool_pages_, hash_mask_, counter_, map.table, map.draw_table,
               slot_owner_, slot_frame_, slot_valid_, hash_, draw_list_);
  timeline.add("virtual.allocate", runtime_.launch(k, 1));
  allocated_ = &map;
}

VirtualPagesPass::Counts VirtualPagesPass::counts() {
  uint32_t c[kCounterWords] = {};
  runtime_.read(counter_, c, sizeof c);
  runtime_.finish();
  if (allocated_) {
    const size_t levels = allocated_->layout.levels.size();
    allocated_->level_drawn.assign(c + 3, c + 3 + levels);
    allocated_->first_drawn.clear();
    allocated_->page_box.clear();
    uint32_t first = c[2];  // the list's end: this light's pages are the last ones
    for (size_t l = 0; l < levels; ++l) first -= c[3 + l];
    for (size_t l = 0; l < levels; first += c[3 + l++]) {
      allocated_->first_drawn.push_back(first);
      const uint32_t* box = c + 3 + kMaxLevels + 4 * l;
      allocated_->page_box.emplace_back(box[0], box[1], box[2], box[3]);
    }
  }
  return {c[0], c[1], c[2]};
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

PageTarget VirtualPagesPass::target(const VirtualMap& map, uint32_t level) const {
  const glm::ivec4 box = map.page_box.at(level);  // pages -> tiles, inclusive
  constexpr int per_page = int(kPageTexels / Rasterizer::kTile);
  return {&map.draw_table,
          level * map.pages() * map.pages(),
          &pool_,
          &draw_list_,
          map.first_drawn.at(level),
          map.level_drawn.at(level),
          {box.x * per_page, box.y * per_page, box.z * per_page + per_page - 1,
           box.w * per_page + per_page - 1}};
}

const cl::Buffer& VirtualPagesPass::pool_image(Timeline& timeline) {
  const uint32_t texels = pool_pages_ * kPageTexels * kPageTexels;
  runtime_.ensure(pool_image_, size_t{texels} * sizeof(float));
  const PixelShape shape = pixel_shape(runtime_, kChunk);
  cl_kernel k = kernel("virtual_pool_image");
  cl::set_args(k, pool_, slot_frame_, frame_, texels, pool_image_);
  timeline.add("readback", runtime_.launch(k, shape.work_items(texels), shape.group));
  return pool_image_;
}

const cl::Buffer& VirtualPagesPass::image(const char* name, const cl::Buffer& src, uint32_t count,
                                          cl::Buffer& out, Timeline& timeline) {
  runtime_.ensure(out, size_t{count} * sizeof(float));
  const PixelShape shape = pixel_shape(runtime_, kChunk);
  cl_kernel k = kernel(name);
  cl::set_args(k, src, count, out);
  timeline.add("readback", runtime_.launch(k, shape.work_items(count), shape.group));
  return out;
}

const cl::Buffer& VirtualPagesPass::table_image(uint32_t light, Timeline& timeline) {
  const VirtualMap& m = maps_.at(light);
  return image("virtual_table_image", m.table, uint32_t(m.page_count()), table_image_, timeline);
}

const cl::Buffer& VirtualPagesPass::level_image(uint32_t light, uint32_t pixels,
                                                Timeline& timeline) {
  return image("virtual_level_image", maps_.at(light).pixel_level, pixels, level_image_, timeline);
}

}  // namespace shadow
