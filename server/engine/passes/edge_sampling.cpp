#include "engine/passes/edge_sampling.hpp"

#include "engine/passes/pcf.hpp"

namespace shadow {

double EdgeSamplingPass::run(const GBuffer& g, uint32_t width, uint32_t height,
                             const std::vector<LightMap>& maps, const Light& light,
                             const ShadowMapSettings& settings, Timeline& timeline) {
  const uint32_t pixels = width * height;
  runtime_.ensure(difference_, size_t{pixels} * sizeof(float));
  runtime_.ensure(no_taps_, 2 * sizeof(float));  // the tap pattern is not read
  timeline.add("edge_sampling.test",
               launch_pcf(runtime_, kernels_, g, pixels, width, maps, light, settings,
                          PcfParams::kEdgeMode, no_taps_, 0u, 0.0f, false, difference_));
  return mean(difference_, width, height, timeline);
}

double EdgeSamplingPass::mean(const cl::Buffer& difference, uint32_t width, uint32_t height,
                              Timeline& timeline) {
  runtime_.ensure(partials_, size_t{height} * 2 * sizeof(float));
  cl_kernel k = kernels_.kernel("edge_sampling.cl", "edge_sampling_partials");
  cl::set_args(k, difference, width, height, partials_);
  timeline.add("edge_sampling", runtime_.launch(k, height));
  std::vector<float> partials(size_t{height} * 2);
  timeline.add("edge_sampling",
               runtime_.read(partials_, partials.data(), partials.size() * sizeof(float)));
  double seen = 0, sum = 0;
  for (uint32_t y = 0; y < height; ++y) {
    seen += partials[2 * y];
    sum += partials[2 * y + 1];
  }
  return seen > 0 ? sum / seen : 0.0;
}

}  // namespace shadow
