// The visible receivers' view-depth range: min and max distance along the camera's forward axis
// over the camera-view pixels that receive shadows. PSM and LiSPSM push their near and far planes
// to it (Kozlov 14.1.2, the PSM paper §6). The G-buffer's resolve writes it per chunk of pixels
// as it writes their positions (kernels/gbuffer.cl), so measuring it is a read of those partials.
#pragma once

#include <optional>

#include "engine/passes/gbuffer.hpp"
#include "engine/psm_fit.hpp"

namespace shadow {

class DepthRangePass {
 public:
  explicit DepthRangePass(const cl::Runtime& runtime) : runtime_(runtime) {}

  // Depths relative to the camera's eye along its unit forward axis (CameraRays::forward);
  // nullopt when no pixel receives shadows. Reads the G-buffer's partials back (one float pair
  // per GBuffer::kPixelChunk pixels), so it waits for the G-buffer.
  std::optional<DepthRange> run(const GBuffer& gbuffer, Timeline& timeline);

 private:
  const cl::Runtime& runtime_;
};

}  // namespace shadow
