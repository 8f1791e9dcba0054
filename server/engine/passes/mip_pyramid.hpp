// Mip pyramids of any device texture (kernels/mip.cl): area-weighted box filter, any size and
// channel count, down to 1x1.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/mip_levels.hpp"
#include "engine/passes/device_texture.hpp"
#include "engine/timeline.hpp"

namespace shadow {

struct MipChain {
  std::vector<MipLevel> levels;  // level 1 (half size) .. the 1x1 level; level 0 is the source
  cl::Buffer storage;            // every level back to back
  uint32_t channels = 1;
  size_t floats = 0;  // used part of storage
};

class MipPyramidPass {
 public:
  MipPyramidPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // Levels 1.. of `src`. `pass` names the timings and the chain, which stays valid until the
  // next run of the same pass.
  const MipChain& run(const DeviceTexture& src, const std::string& pass, Timeline& timeline);
  // The chain `pass` last made, or null.
  const MipChain* last(const std::string& pass) const {
    const auto it = chains_.find(pass);
    return it == chains_.end() ? nullptr : &it->second;
  }
  // Levels 1.. of the `width` x `height` x `channels` texture at the start of `storage`, each
  // written after it at `levels[i].offset` texels past level 0's end (mip_levels' offsets), in
  // half floats when `half` (CSM bases). `storage` must hold them all.
  void run_in_place(const cl::Buffer& storage, uint32_t width, uint32_t height, uint32_t channels,
                    bool half, const std::string& pass, Timeline& timeline);
  void warm_up() {
    kernels_.kernel("mip.cl", "mip_downsample");
    kernels_.kernel("mip.cl", "mip_downsample", "-DMIP_HALF");
  }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  std::map<std::string, MipChain> chains_;  // by pass
};

}  // namespace shadow
