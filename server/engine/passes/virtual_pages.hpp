// Virtual shadow maps' pages (issue 53; kernels/virtual_pages.cl): the pages of a directional
// light's clipmap (engine/light/virtual_levels.hpp) that the camera view's pixels read, marked a
// byte per page (pages x pages a level, finest level first), then given slots of the request's
// pool in page order. The rasterizer draws them (PageTarget) and pcf.cl's VIRTUAL reads them.
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
  DirectionalClipmap clipmap;
  cl::Buffer marks;        // a byte per page (1: read), levels x pages^2
  cl::Buffer table;        // a pool slot per page (kNoPage: none), levels x pages^2
  cl::Buffer level_ndc;    // per level, its world -> texture NDC (float16, column-major)
  cl::Buffer pixel_level;  // per camera pixel, its level's index (kNoLevel: none)
  // After VirtualPagesPass::counts(): each level's slots in the pool, consecutive from its first,
  // and the bounding box of its pages that have slots (x0, y0, x1, y1, in pages).
  std::vector<uint32_t> level_slots, first_slot;
  std::vector<glm::ivec4> page_box;
  uint32_t pages() const { return clipmap.texels / kPageTexels; }  // across a level
  size_t page_count() const { return clipmap.levels.size() * size_t{pages()} * pages(); }
};

class VirtualPagesPass {
 public:
  VirtualPagesPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // A request's pool of `pool_pages` pages, none given yet; the lights' maps follow.
  void begin(uint32_t pool_pages);

  // Light `light`'s map: the marks of `view`'s `pixels` (rows of `width`; `camera`'s), read at
  // the level their light-space footprint times 2^`bias` selects, with `reach` texels around
  // each (a filter's taps), and each pixel's level; pixels farther than `coarsen_beyond` from
  // the eye read a level coarser per doubling of the distance past it. Valid until the next
  // begin().
  VirtualMap& mark(uint32_t light, const GBuffer& view, uint32_t width, uint32_t pixels,
                   const Camera& camera, const DirectionalClipmap& clipmap, double bias,
                   float reach, Timeline& timeline,
                   float coarsen_beyond = std::numeric_limits<float>::infinity());
  // Slots of the pool for `map`'s marked pages, in page order after the lights' kept before it
  // (keep()).
  void allocate(VirtualMap& map, Timeline& timeline);

  struct Counts {
    uint64_t requested = 0;  // pages marked, the kept lights' and the last allocate()'s
    uint64_t resident = 0;   // of them, those given a slot
  };
  // Reads them (one read; waits for the queue), and the last allocate()'s map's level slots.
  Counts counts();
  // Keeps the last allocate()'s slots: the next light's follow them. Until then, allocating
  // again (after marking again, coarser) replaces them.
  void keep();

  struct PixelCounts {
    uint64_t outside = 0;    // pixels no level holds
    uint64_t coarsened = 0;  // pixels that read a coarser level than their footprint's
  };
  PixelCounts pixel_counts();  // the last mark()'s (reads them back)

  const cl::Buffer& pool() const { return pool_; }
  // Level `level` of `map` as the rasterizer's target (after counts()).
  PageTarget target(const VirtualMap& map, uint32_t level) const;
  uint32_t pool_pages() const { return pool_pages_; }
  void warm_up();

 private:
  static constexpr uint32_t kChunk = 64;  // PIXEL_CHUNK in virtual_pages.cl
  // virtual_allocate's counter: slots, marks, then per level its slots and its pages' box.
  static constexpr size_t kCounterWords = 2 + 5 * kMaxLevels;
  cl_kernel mark_kernel();
  cl_kernel allocate_kernel();
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  std::vector<VirtualMap> maps_;  // by light
  cl::Buffer pool_, counter_, first_pages_, outside_, slot_page_;
  VirtualMap* allocated_ = nullptr;  // the last allocate()'s
  uint32_t pool_pages_ = 0;
  // Members: their writes are asynchronous.
  std::vector<glm::vec2> first_page_table_;
  std::vector<std::vector<glm::mat4>> level_ndc_;
  size_t work_items_ = 0;
  uint32_t levels_ = 0;    // the last allocate()'s
  uint32_t kept_[2] = {};  // the slots and marks of the lights kept
  Counts last_;
};

}  // namespace shadow
