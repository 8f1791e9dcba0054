// How a per-pixel kernel written in strips (a work-item per PIXEL_CHUNK pixels: pcf.cl, pcss.cl's
// pcss, texel_density.cl, gbuffer.cl) runs on the device profile's shape (issue 42).
// - CPU shape: the kernel as written, a strip per work-item in work-groups of one, the strip's
//   loops vectorized by PoCL.
// - GPU shape: the same source built with -DPIXEL_CHUNK=1 -DGROUP_SIZE=<group>, a work-item per
//   pixel in work-groups of the profile's size. Each pixel's arithmetic is the same expressions
//   (contraction off, division and sqrt correctly rounded: kernels/prelude.cl), so both shapes
//   give the same bits on a device, and one source stays the truth for both.
#pragma once

#include <cstdint>
#include <string>

#include "engine/cl/runtime.hpp"

namespace shadow {

struct PixelShape {
  uint32_t strip = 1;   // pixels per work-item
  size_t group = 1;     // work-items per work-group
  std::string options;  // -D options of the shape ("" for the kernel as written)

  size_t work_items(uint32_t pixels) const { return (size_t{pixels} + strip - 1) / strip; }
  // A kernel's own options with the shape's.
  std::string with(const std::string& own) const {
    return options.empty() ? own : own.empty() ? options : own + " " + options;
  }
};

// The CPU shape: strips of `strip` pixels (the kernel's PIXEL_CHUNK).
inline PixelShape strip_shape(uint32_t strip) {
  return {strip, 1, ""};
}

// The shape `profile` asks for, for a kernel whose strips are `strip` pixels.
inline PixelShape pixel_shape(const cl::DeviceProfile& profile, uint32_t strip) {
  if (profile.shape != cl::KernelShape::kGpu) return strip_shape(strip);
  return {1, profile.group_size,
          "-DPIXEL_CHUNK=1 -DGROUP_SIZE=" + std::to_string(profile.group_size)};
}

inline PixelShape pixel_shape(const cl::Runtime& runtime, uint32_t strip) {
  return pixel_shape(runtime.device_info().profile(), strip);
}

// Kernels that give each chunk of their input a work-group (reductions, binning; -DGROUP): one
// work-item on the CPU shape, the profile's work-group on the GPU shape.
inline size_t chunk_group(const cl::Runtime& runtime) {
  const cl::DeviceProfile& profile = runtime.device_info().profile();
  return profile.shape == cl::KernelShape::kGpu ? profile.group_size : 1;
}
// The build option of such a kernel's work-group ("" for one work-item).
inline std::string group_option(size_t group) {
  return group == 1 ? std::string() : "-DGROUP=" + std::to_string(group);
}

}  // namespace shadow
