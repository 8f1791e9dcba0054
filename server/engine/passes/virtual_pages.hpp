// Virtual shadow maps' pages (issue 53; kernels/virtual_pages.cl): the pages of a light's levels
// (engine/light/virtual_levels.hpp: a clipmap, or perspective mip chains) that the camera view's
// pixels read, marked a byte per page (pages x pages a level, in the levels' order), then given
// slots of the request's pool. While the workspace keeps (a sequence's frames), a page keeps its
// slot and its texels from frame to frame until a change makes them stale; the least recently
// marked slots go first. The rasterizer draws the pages whose texels are not valid (PageTarget) and
// pcf.cl's VIRTUAL reads them all.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/runtime.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/light/virtual_levels.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/rasterizer.hpp"

namespace shadow {

inline constexpr uint32_t kNoPage = 0xffffffffu;  // NO_PAGE in the kernels
inline constexpr uint8_t kNoLevel = 0xff;         // NO_LEVEL in virtual_pages.cl
inline constexpr size_t kPageBytes = size_t{kPageTexels} * kPageTexels * sizeof(float);

// A light's virtual map on the device: what the raster draws and the filters read.
struct VirtualMap {
  VirtualLevels layout;
  cl::Buffer marks;         // a byte per page (1: read), levels x pages^2
  cl::Buffer table;         // a pool slot per page (kNoPage: none), levels x pages^2
  cl::Buffer draw_table;    // the slots of the pages drawn this frame (kNoPage elsewhere)
  cl::Buffer level_ndc;     // per level, its world -> texture NDC (float16, column-major)
  cl::Buffer level_texels;  // per level, its texels across (VirtualLevels::extent)
  cl::Buffer pixel_level;   // per camera pixel, its level's index (kNoLevel: none)
  // After VirtualPagesPass::counts(): each level's pages drawn this frame (consecutive in the
  // pass's draw list from first_drawn) and their bounding box (x0, y0, x1, y1, in pages).
  std::vector<uint32_t> level_drawn, first_drawn;
  std::vector<glm::ivec4> page_box;
  // What its valid pages were drawn from (the workspace's key of the light, the scene's copy and
  // the levels), and each instance's world box then: a caster that moves stales its pages.
  uint64_t drawn_from = 0;
  std::vector<InstanceBounds> casters;
  uint32_t pages() const { return layout.texels / kPageTexels; }  // across a level
  size_t page_count() const { return layout.levels.size() * size_t{pages()} * pages(); }
};

class VirtualPagesPass {
 public:
  VirtualPagesPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // A frame's pool of `pool_pages` pages. Keeping (a sequence's next frame, the same pool), the
  // pages of earlier frames stay; otherwise every slot starts empty.
  void begin(uint32_t pool_pages, bool keeping, Timeline& timeline);

  // Light `light`'s map: the marks of `view`'s `pixels` (rows of `width`; `camera`'s), read at
  // the level their light-space footprint times 2^`bias` selects, with `reach` texels around
  // each (a filter's taps), and each pixel's level; pixels farther than `coarsen_beyond` from
  // the eye read a level coarser per doubling of the distance past it. With PCSS, `soft`
  // (pcss_search_bound) makes a pixel's level one whose texels hold its blocker search within
  // `reach`. Valid until the next begin().
  VirtualMap& mark(uint32_t light, const GBuffer& view, uint32_t width, uint32_t pixels,
                   const Camera& camera, const VirtualLevels& layout, double bias, float reach,
                   Timeline& timeline,
                   float coarsen_beyond = std::numeric_limits<float>::infinity(),
                   const glm::vec4& soft = glm::vec4(0.0f));
  // The pages `map`'s marks ask for (reads them; waits for the queue).
  uint64_t marked(const VirtualMap& map, Timeline& timeline);
  // The slots of light `light`'s pages that a change makes stale: all of them, or those whose
  // light-space squares meet `boxes` (x0, y0, x1, y1 in the layout's light space).
  void invalidate(uint32_t light, bool all, const std::vector<glm::vec4>& boxes, uint32_t texels,
                  Timeline& timeline);
  // Slots of the pool for `map`'s marked pages (light `light`'s), after the lights' before it.
  void allocate(uint32_t light, VirtualMap& map, Timeline& timeline);

  struct Counts {
    uint64_t held = 0;    // slots this frame's pages hold, every light since begin()
    uint64_t marked = 0;  // pages marked
    uint64_t drawn = 0;   // pages whose texels are drawn this frame (not kept)
  };
  // Reads them (one read; waits for the queue), and the last allocate()'s map's levels.
  Counts counts();

  struct PixelCounts {
    uint64_t outside = 0;    // pixels no level holds
    uint64_t coarsened = 0;  // pixels that read a coarser level than their footprint's
  };
  PixelCounts pixel_counts();  // the last mark()'s (reads them back)

  const cl::Buffer& pool() const { return pool_; }
  // PRODUCT_VIRTUAL_PAGES's images, as floats on the device (valid until the next call of the
  // same): the pool with only this frame's slots (1.0 in the others), light `light`'s page
  // tables (-1: no slot) and its pixels' levels (NaN: none).
  const cl::Buffer& pool_image(Timeline& timeline);
  const cl::Buffer& table_image(uint32_t light, Timeline& timeline);
  const cl::Buffer& level_image(uint32_t light, uint32_t pixels, Timeline& timeline);
  const VirtualMap& map(uint32_t light) const { return maps_.at(light); }
  uint32_t pool_pages() const { return pool_pages_; }
  // Level `level` of `map` as the rasterizer's target (after counts()).
  PageTarget target(const VirtualMap& map, uint32_t level) const;
  void warm_up();

 private:
  static constexpr uint32_t kChunk = 64;  // PIXEL_CHUNK in virtual_pages.cl
  // virtual_allocate's counter: slots held, marks, pages drawn, then per level its pages drawn
  // and their box.
  static constexpr size_t kCounterWords = 3 + 5 * kMaxLevels;
  cl_kernel kernel(const char* name);
  // Kernel `name` over `count` values of `src` into `out` (the readback's float images).
  const cl::Buffer& image(const char* name, const cl::Buffer& src, uint32_t count, cl::Buffer& out,
                          Timeline& timeline);
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  std::vector<VirtualMap> maps_;  // by light
  cl::Buffer pool_, counter_, first_pages_, to_light_, outside_, marked_;
  // Per slot: its page's key, the frame that last marked it, whether its texels are valid; the
  // keys' hash table, and this frame's pages to draw (slot, page).
  cl::Buffer slot_owner_, slot_frame_, slot_valid_, hash_, draw_list_, boxes_;
  cl::Buffer pool_image_, table_image_, level_image_;
  uint32_t pool_pages_ = 0, hash_mask_ = 0, frame_ = 0;
  VirtualMap* allocated_ = nullptr;  // the last allocate()'s
  // Light `light`'s levels to the device: their first pages (first_pages_, which marking and
  // allocation read) and matrices (map.level_ndc, which the filters read).
  void write_levels(uint32_t light, VirtualMap& map, const char* pass, Timeline& timeline);
  // Per light, what write_levels() wrote: members, as the writes are asynchronous.
  struct LevelTables {
    std::vector<glm::vec2> first_pages;
    std::vector<glm::mat4> ndc, to_light;  // to_light: marking's light space (mark())
    std::vector<uint32_t> texels;
  };
  std::vector<LevelTables> level_tables_;
  std::vector<glm::vec4> box_table_;
  size_t work_items_ = 0;
};

}  // namespace shadow
