// A float texture already on the device (shadow map, visibility, later atlases and CSM bases):
// row-major, row 0 at the top, channels interleaved. Filters take this so they work on any of them.
#pragma once

#include <cstdint>

#include "engine/cl/runtime.hpp"

namespace shadow {

struct DeviceTexture {
  const cl::Buffer* buffer = nullptr;
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t channels = 1;

  size_t texels() const { return size_t{width} * height; }
  size_t floats() const { return texels() * channels; }
};

}  // namespace shadow
