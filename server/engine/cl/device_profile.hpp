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
  // Launch slices (Runtime::launch): each runs alone on the device, so a slice is how long one
  // client's work can hold another's. The first is one work-group per compute unit (a work-item
  // may be a strip of 64 pixels or a whole row), later ones are sized by the last one's measured
  // rate to about slice_ms: 20 ms keeps a bystander's wait short (issue 51 asks at most ~100 ms)
  // while a slice's own cost, ~0.1 ms here, stays under 1%.
  size_t first_slice_groups = 1;
  double slice_ms = 20;
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
