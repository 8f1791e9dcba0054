// Virtual shadow maps' page marking (issue 53; kernels/virtual_pages.cl): the pages of a
// directional light's clipmap (engine/light/virtual_levels.hpp) that the camera view's pixels
// read, a byte per page (1: read), pages x pages a level, finest level first.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/runtime.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/light/virtual_levels.hpp"
#include "engine/passes/gbuffer.hpp"

namespace shadow {

class VirtualPagesPass {
 public:
  VirtualPagesPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // The marks of `view`'s `pixels` (rows of `width`; `camera`'s), read at the level their
  // light-space footprint times 2^`bias` selects, with `reach` texels around each (a filter's
  // taps). Valid until the next run; `outside` (pixels no level holds) after the queue finishes.
  const cl::Buffer& mark(const GBuffer& view, uint32_t width, uint32_t pixels, const Camera& camera,
                         const DirectionalClipmap& clipmap, double bias, uint32_t reach,
                         Timeline& timeline);
  // Pixels of the last mark() that no level holds (reads them back).
  uint64_t outside();
  void warm_up();

 private:
  static constexpr uint32_t kChunk = 64;  // PIXEL_CHUNK in virtual_pages.cl
  cl_kernel kernel();
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer marks_, first_pages_, outside_;
  std::vector<glm::vec2> first_page_table_;  // a member: the write is asynchronous
  size_t work_items_ = 0;
};

}  // namespace shadow
