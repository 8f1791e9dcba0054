#include "engine/plan/mip_levels.hpp"

#include <algorithm>

namespace shadow {

std::vector<MipLevel> mip_levels(uint32_t width, uint32_t height) {
  std::vector<MipLevel> levels;
  size_t offset = 0;
  while (width > 1 || height > 1) {
    width = std::max(1u, width / 2);
    height = std::max(1u, height / 2);
    levels.push_back({width, height, offset});
    offset += size_t{width} * height;
  }
  return levels;
}

uint64_t mip_chain_texels(uint32_t width, uint32_t height) {
  uint64_t texels = uint64_t{width} * height;
  for (const MipLevel& l : mip_levels(width, height)) texels += uint64_t{l.width} * l.height;
  return texels;
}

}  // namespace shadow
