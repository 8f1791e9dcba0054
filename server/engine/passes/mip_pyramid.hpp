// Mip pyramids of any device texture (kernels/mip_pyramid.cl): area-weighted box filter, any size
// and channel count, down to 1x1. The device profile's GPU shape runs its mip_gpu_downsample
// instead (a work-item per texel and channel), the same levels bit for bit.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/passes/device_texture.hpp"
#include "engine/plan/mip_levels.hpp"

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
    for (bool half : {false, true}) kernel(half);
  }

 private:
  // The downsampling kernel of the device's shape, for float or half texels.
  cl_kernel kernel(bool half);
  // Enqueues one level: `w` x `h` at `src_offset` of `src` into `w2` x `h2` at `dst_offset` of
  // `dst` (offsets in elements).
  cl::Events downsample(cl_kernel k, const cl::Buffer& src, cl_ulong src_offset, uint32_t w,
                        uint32_t h, uint32_t channels, const cl::Buffer& dst, cl_ulong dst_offset,
                        uint32_t w2, uint32_t h2);

  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  std::map<std::string, MipChain> chains_;  // by pass
};

}  // namespace shadow
