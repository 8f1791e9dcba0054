// Percentage-closer filtering (kernels/pcf.cl): bilinear 2x2 and N-tap Poisson-disk PCF of the
// shadow test, visibility per camera pixel. Averages visibilities, never depths.
#pragma once

#include "engine/light/light_space.hpp"
#include "engine/passes/depth_range.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/pixel_shape.hpp"

namespace shadow {

struct PcfParams {
  enum class Mode { kBilinear = 0, kPoisson = 1 };  // as PCF_* in pcf.cl
  static constexpr int kNearestMode = 2;            // PCF_NEAREST: the hard test (ShadowTestPass)
  static constexpr int kEdgeMode = 3;  // PCF_EDGE: |hard - bilinear| (EdgeSamplingPass)
  Mode mode = Mode::kBilinear;
  uint32_t taps = 16;   // Poisson: 1..64
  float radius = 2.0f;  // Poisson: in shadow-map texels
  bool rotate = true;   // Poisson: rotate the pattern per pixel (noise instead of banding)
};

// pcf.cl's work-items on the CPU shape: one per strip of this many pixels (PIXEL_CHUNK).
inline constexpr uint32_t kPcfStrip = 64;
// pcf.cl's shape on `runtime`'s device profile (engine/passes/pixel_shape.hpp).
inline PixelShape pcf_shape(const cl::Runtime& runtime) {
  return pixel_shape(runtime, kPcfStrip);
}

// pcf.cl's kernel over `pixels` camera pixels of `g` against `maps`, in `mode` (PCF_*: a
// PcfParams::Mode, kNearestMode or kEdgeMode), written to `out`; `taps` holds at least one tap
// (read only by Poisson). With `depth`, a single map's launch also writes the view-depth range's
// partials, one per strip (VIEW_DEPTH). The one place its arguments are set: PcfPass,
// ShadowTestPass and EdgeSamplingPass launch it here.
cl::Events launch_pcf(const cl::Runtime& runtime, cl::Kernels& kernels, const GBuffer& g,
                      uint32_t pixels, uint32_t width, const std::vector<LightMap>& maps,
                      const Light& light, const ShadowMapSettings& settings, int mode,
                      const cl::Buffer& taps, uint32_t tap_count, float radius, bool rotate,
                      const cl::Buffer& out, const ViewDepthOut* depth = nullptr);

// Builds pcf.cl with `options` before its first launch (warm-up). ShadowTestPass and
// EdgeSamplingPass launch it in their modes through launch_pcf and name no kernel file.
inline void warm_pcf(cl::Kernels& kernels, const std::string& options) {
  kernels.kernel("pcf.cl", "pcf", options);
}

class PcfPass {
 public:
  static constexpr uint32_t kMaxTaps = 64;

  PcfPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // 1 lit, 0 shadowed, fractions in between, NaN where the camera sees nothing; a cube's
  // pixels each filtered in their face (taps off it are lit), in one launch. `width` is the
  // camera's (per-pixel rotation hashes the pixel's coordinates). Valid until the next run.
  const cl::Buffer& run(const GBuffer& gbuffer, uint32_t pixels, uint32_t width,
                        const std::vector<LightMap>& maps, const Light& light,
                        const ShadowMapSettings& settings, const PcfParams& params,
                        Timeline& timeline);
  void warm_up() {
    for (const char* options : {"", "-DCUBE_FACES", "-DVIRTUAL"})
      warm_pcf(kernels_, pcf_shape(runtime_).with(options));
  }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer visibility_, taps_;
  std::vector<glm::vec2> pattern_;
  uint32_t tap_count_ = 0;  // the pattern now in taps_
};

}  // namespace shadow
