#include "engine/passes/view_samples.hpp"

#include <array>
#include <cmath>

namespace shadow {

std::vector<Sample> ViewSamplesPass::run(const GBuffer& view, uint32_t width, uint32_t height,
                                         Timeline& timeline, std::vector<uint32_t>* cells) {
  constexpr uint32_t kCount = kSampleColumns * kSampleRows;
  using Packed = std::array<float, 8>;  // position, 0, normal, 0 (a float8)
  runtime_.ensure(samples_, kCount * sizeof(Packed));
  cl_kernel k = kernels_.kernel("view_samples.cl", "view_samples");
  cl::set_args(k, view.position, view.normal, width, height, kSampleColumns, kSampleRows, samples_);
  timeline.add("view_samples", runtime_.launch(k, kCount));
  std::vector<Packed> packed(kCount);
  timeline.add("view_samples", runtime_.read(samples_, packed.data(), kCount * sizeof(Packed)));
  std::vector<Sample> out;
  if (cells) cells->clear();
  for (uint32_t i = 0; i < kCount; ++i) {
    const Packed& s = packed[i];
    if (std::isnan(s[0]) || std::isnan(s[1]) || std::isnan(s[2])) continue;  // nothing seen
    out.push_back({{s[0], s[1], s[2]}, {s[4], s[5], s[6]}});
    if (cells) cells->push_back(i);
  }
  return out;
}

}  // namespace shadow
