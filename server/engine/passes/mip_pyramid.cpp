#include "engine/passes/mip_pyramid.hpp"

#include <algorithm>

namespace shadow {
namespace {
constexpr uint32_t kChunk = 512;  // MIP_CHUNK in mip.cl
}  // namespace

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
  cl_kernel k = kernels_.kernel("mip.cl", "mip_downsample");
  uint32_t w = src.width, h = src.height;
  for (size_t i = 0; i < chain.levels.size(); ++i) {
    const MipLevel& l = chain.levels[i];
    const cl_ulong src_offset = i == 0 ? 0 : chain.levels[i - 1].offset;
    cl::set_args(k, i == 0 ? *src.buffer : chain.storage, src_offset, w, h, src.channels,
                 chain.storage, cl_ulong{l.offset}, l.width, l.height);
    w = l.width;
    h = l.height;
    timeline.add(pass, runtime_.launch(k, size_t{l.height} * ((l.width + kChunk - 1) / kChunk)));
  }
  return chain;
}

void MipPyramidPass::run_in_place(const cl::Buffer& storage, uint32_t width, uint32_t height,
                                  uint32_t channels, bool half, const std::string& pass,
                                  Timeline& timeline) {
  cl_kernel k = kernels_.kernel("mip.cl", "mip_downsample", half ? "-DMIP_HALF" : "");
  const std::vector<MipLevel> levels = mip_levels(width, height);
  const size_t base = size_t{width} * height;
  cl_ulong src_offset = 0;
  uint32_t w = width, h = height;
  for (const MipLevel& l : levels) {
    const cl_ulong dst_offset = (base + l.offset) * channels;
    cl::set_args(k, storage, src_offset, w, h, channels, storage, dst_offset, l.width, l.height);
    timeline.add(pass, runtime_.launch(k, size_t{l.height} * ((l.width + kChunk - 1) / kChunk)));
    src_offset = dst_offset;
    w = l.width;
    h = l.height;
  }
}

}  // namespace shadow
