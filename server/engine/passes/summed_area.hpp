// Summed-area tables of any device texture (kernels/summed_area.cl) and the box filter on them.
// The table holds doubles that are exact multiples of a power-of-two quantum (see summed_area.cl),
// so box sums keep their precision anywhere in the texture (an 8192^2 float SAT does not). The
// device profile's GPU shape runs its sat_gpu_* kernels instead: rows, strips and columns in
// parallel, the same table bit for bit.
#pragma once

#include <map>
#include <string>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/passes/device_texture.hpp"

namespace shadow {

struct SummedAreaTable {
  cl::Buffer sums;  // double per texel and channel: the inclusive sum over [0, x] x [0, y]
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t channels = 1;
};

class SummedAreaPass {
 public:
  static constexpr uint32_t kMaxChannels = 64;  // as SAT_MAX_CHANNELS in summed_area.cl

  SummedAreaPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // `pass` names the timings and the table, which stays valid until the next run of the same
  // pass.
  const SummedAreaTable& run(const DeviceTexture& src, const std::string& pass, Timeline& timeline);
  // The table `pass` last made, or null.
  const SummedAreaTable* last(const std::string& pass) const {
    const auto it = tables_.find(pass);
    return it == tables_.end() ? nullptr : &it->second;
  }
  // The per-channel average over the (2 rx + 1) x (2 ry + 1) box around each texel, clipped to
  // the texture, as floats in `out` (grown to fit).
  void box_filter(const SummedAreaTable& sat, uint32_t rx, uint32_t ry, cl::Buffer& out,
                  const std::string& pass, Timeline& timeline);
  void warm_up();

 private:
  bool gpu_shape() const;
  // The GPU shape's program options: its work-group size.
  std::string gpu_options() const;
  void run_gpu(const DeviceTexture& src, SummedAreaTable& table, const std::string& pass,
               Timeline& timeline);

  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  std::map<std::string, SummedAreaTable> tables_;  // by pass
  cl::Buffer offsets_, item_max_, scale_;
  cl::Buffer max_, block_sums_;  // the GPU shape's largest |value|, its column blocks' sums
};

}  // namespace shadow
