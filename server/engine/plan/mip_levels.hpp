// The sizes of a mip chain, for the passes that build one and for validation and admission,
// which size them before any device exists. Pure host code.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace shadow {

struct MipLevel {
  uint32_t width = 0;
  uint32_t height = 0;
  size_t offset = 0;  // in floats, into MipChain::levels
};

// Level sizes below `width` x `height`: max(1, floor(w / 2)) each step, until 1x1.
std::vector<MipLevel> mip_levels(uint32_t width, uint32_t height);
// Texels of level 0 and every level after it.
uint64_t mip_chain_texels(uint32_t width, uint32_t height);

}  // namespace shadow
