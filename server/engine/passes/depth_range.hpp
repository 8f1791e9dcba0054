// The visible receivers' view-depth range (kernels/depth_range.cl): min and max distance along the
// camera's forward axis over the camera-view pixels that receive shadows. PSM pushes its virtual
// camera's near and far planes to it (Kozlov 14.1.2, the paper §6).
#pragma once

#include <optional>
#include <string>

#include "engine/light/psm_fit.hpp"
#include "engine/passes/gbuffer.hpp"

namespace shadow {

// Where a pass that reads the camera view anyway writes the range's partials beside its own
// output (pcf.cl's VIEW_DEPTH: the quality probe's hard test, one (min, max) per strip).
struct ViewDepthOut {
  glm::vec4 eye, forward;  // as DepthRangePass measures along them
  const cl::Buffer* partials = nullptr;
};

class DepthRangePass {
 public:
  static constexpr uint32_t kChunk =
      4096;  // pixels per work-item, as DEPTH_CHUNK in depth_range.cl

  DepthRangePass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // Depths relative to `camera.eye` along the unit forward axis (eye -> target); nullopt when
  // no pixel receives shadows. Reads the partials back (a few hundred floats), so it waits for
  // the G-buffer.
  std::optional<DepthRange> run(const GBuffer& gbuffer, const Camera& camera, Timeline& timeline);
  void warm_up() { partials_kernel(); }

  // The same range from another pass's `count` partials: `out` (for `camera`) to hand that pass,
  // then `read` once it has run (the same bits as run(): pcf.cl reduces as depth_range.cl does).
  ViewDepthOut out(const Camera& camera, uint32_t count);
  std::optional<DepthRange> read(uint32_t count, Timeline& timeline);

 private:
  // view_depth_partials in the device profile's shape: a work-item per chunk of kChunk pixels
  // (view_depth_partials), or a work-group (view_depth_partials_gpu, issue 42; pixel_shape.hpp's
  // chunk_group); the same partials.
  cl_kernel partials_kernel();
  std::optional<DepthRange> combine(const cl::Buffer& partials, uint32_t count,
                                    const std::string& pass, Timeline& timeline);

  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer partials_, strips_;
};

}  // namespace shadow
