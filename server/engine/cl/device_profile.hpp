// The shape of kernels a device runs (issue 42). The CPU shape gives a work-item a strip, a tile
// or a chunk and lets PoCL vectorize across work-items (docs: "What is fast on PoCL's CPU
// backend"); the GPU shape gives a work-item a pixel or a texel, in work-groups that share local
// memory. Both compute the same results; each pass picks its kernels by the profile.
#pragma once

#include <cstddef>
#include <string>

#include "engine/cl/device_choice.hpp"

namespace shadow::cl {

enum class KernelShape { kCpu, kGpu };
const char* shape_name(KernelShape shape);  // "cpu", "gpu"

// Tests and benches, which build their device without a command line, read the choice here; the
// server's --kernel-profile overrides it.
inline constexpr const char* kKernelProfileEnvironment = "SHADOW_KERNEL_PROFILE";

struct DeviceProfile {
  KernelShape shape = KernelShape::kCpu;
  // The GPU shape's work-group size: 256, or the device's largest below it (a power of two).
  size_t group_size = 1;
  // Work-items per launch slice, so that a cancel stops within a slice or two (Runtime::launch),
  // in proportion to the device's compute units: on the CPU shape 4096 strips per unit (two
  // cores: 8192 strips, ~0.1 s of the heaviest pass here); on the GPU shape 65536 work-items per
  // unit (32 rounds of the 2048 threads a unit holds: 8.6M on a 132-unit H200), since a GPU
  // runs a thousand times more work-items in that time.
  size_t slice_items = kCpuSliceItemsPerUnit;
  static constexpr size_t kCpuSliceItemsPerUnit = 4096, kGpuSliceItemsPerUnit = 65536;
};

// For `device` with `max_group_size` (CL_DEVICE_MAX_WORK_GROUP_SIZE): `choice` is "cpu", "gpu" or
// "auto"/"" (GPUs and accelerators the GPU shape, else the CPU shape). Throws DeviceChoiceError
// naming `setting` for any other choice.
DeviceProfile make_profile(const DeviceRecord& device, size_t max_group_size,
                           const std::string& choice, const std::string& setting);

// `flag` (the server's --kernel-profile) when given, else $SHADOW_KERNEL_PROFILE, else "auto";
// `setting` names where it came from.
std::string resolve_profile_choice(const std::string& flag, std::string* setting);

}  // namespace shadow::cl
