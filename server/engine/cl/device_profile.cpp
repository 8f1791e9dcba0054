#include "engine/cl/device_profile.hpp"

#include <algorithm>
#include <cstdlib>

namespace shadow::cl {

const char* shape_name(KernelShape shape) {
  return shape == KernelShape::kGpu ? "gpu" : "cpu";
}

DeviceProfile make_profile(const DeviceRecord& device, size_t max_group_size,
                           const std::string& choice, const std::string& setting) {
  KernelShape shape;
  if (choice == "cpu") {
    shape = KernelShape::kCpu;
  } else if (choice == "gpu") {
    shape = KernelShape::kGpu;
  } else if (choice.empty() || choice == "auto") {
    shape = device.type == DeviceType::kGpu || device.type == DeviceType::kAccelerator
                ? KernelShape::kGpu
                : KernelShape::kCpu;
  } else {
    throw DeviceChoiceError(setting + " '" + choice +
                            "' is not a kernel profile: cpu, gpu or auto");
  }
  DeviceProfile p;
  p.shape = shape;
  const size_t units = std::max<size_t>(device.compute_units, 1);
  p.first_slice_groups = units;
  if (shape == KernelShape::kGpu) {
    p.group_size = 1;
    while (p.group_size * 2 <= 256 && p.group_size * 2 <= max_group_size) p.group_size *= 2;
  }
  return p;
}

std::string resolve_profile_choice(const std::string& flag, std::string* setting) {
  if (!flag.empty()) {
    *setting = "--kernel-profile";
    return flag;
  }
  *setting = kKernelProfileEnvironment;
  const char* env = std::getenv(kKernelProfileEnvironment);
  return env ? env : "";
}

}  // namespace shadow::cl
