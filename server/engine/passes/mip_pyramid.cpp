#include "engine/passes/mip_pyramid.hpp"

#include <algorithm>
#include <string>

namespace shadow {
namespace {
constexpr uint32_t kChunk = 512;  // MIP_CHUNK in mip_pyramid.cl
}  // namespace

cl_kernel MipPyramidPass::kernel(bool half) {
  const cl::DeviceProfile& profile = runtime_.device_info().profile();
  if (profile.shape == cl::KernelShape::kGpu)
    return kernels_.kernel(
        "mip_pyramid.cl", "mip_gpu_downsample",
        "-DGROUP=" + std::to_string(profile.group_size) + (half ? " -DMIP_HALF" : ""));
  return kernels_.kernel("mip_pyramid.cl", "mip_downsample", half ? "-DMIP_HALF" : "");
}

cl::Events MipPyramidPass::downsample(cl_kernel k, const cl::Buffer& src, cl_ulong src_offset,
                                      uint32_t w, uint32_t h, uint32_t channels,
                                      const cl::Buffer& dst, cl_ulong dst_offset, uint32_t w2,
                                      uint32_t h2) {
  cl::set_args(k, src, src_offset, w, h, channels, dst, dst_offset, w2, h2);
  const cl::DeviceProfile& profile = runtime_.device_info().profile();
  if (profile.shape == cl::KernelShape::kGpu)  // a work-item per texel
    return runtime_.launch(k, size_t{w2} * h2, profile.group_size);
  return runtime_.launch(k, size_t{h2} * ((w2 + kChunk - 1) / kChunk));
}

const MipChain& MipPyramidPass::run(const DeviceTexture& src, const std::string& pass,
                                    Timeline& timeline) {
  MipChain& chain = chains_[pass];
  chain.levels = mip_levels(src.width, src.height);
  chain.channels = src.channels;
  chain.floats = 0;
  for (MipLevel& l : chain.levels) {
    l.offset *= src.channels;
    chain.floats += size_t{l.width} * l.height * src.channels;
  }
  runtime_.ensure(chain.storage, chain.floats * sizeof(float));
  cl_kernel k = kernel(false);
  uint32_t w = src.width, h = src.height;
  for (size_t i = 0; i < chain.levels.size(); ++i) {
    const MipLevel& l = chain.levels[i];
    const cl_ulong src_offset = i == 0 ? 0 : chain.levels[i - 1].offset;
    timeline.add(pass,
                 downsample(k, i == 0 ? *src.buffer : chain.storage, src_offset, w, h, src.channels,
                            chain.storage, cl_ulong{l.offset}, l.width, l.height));
    w = l.width;
    h = l.height;
  }
  return chain;
}

void MipPyramidPass::run_in_place(const cl::Buffer& storage, uint32_t width, uint32_t height,
                                  uint32_t channels, bool half, const std::string& pass,
                                  Timeline& timeline) {
  cl_kernel k = kernel(half);
  const std::vector<MipLevel> levels = mip_levels(width, height);
  const size_t base = size_t{width} * height;
  cl_ulong src_offset = 0;
  uint32_t w = width, h = height;
  for (const MipLevel& l : levels) {
    const cl_ulong dst_offset = (base + l.offset) * channels;
    timeline.add(pass, downsample(k, storage, src_offset, w, h, channels, storage, dst_offset,
                                  l.width, l.height));
    src_offset = dst_offset;
    w = l.width;
    h = l.height;
  }
}

}  // namespace shadow
