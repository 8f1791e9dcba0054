// Which OpenCL device the engine runs on. A SPEC names one by position, "P:D" (platform P as
// the ICD loader lists them, device D within it), or by a case-insensitive substring of its
// platform's name or vendor or its own name ("nvidia", "pocl": PoCL's platform is named
// "Portable Computing Language", its vendor "The pocl project"). Without a SPEC: a GPU when there
// is one, else a CPU device, else the first device (a farm's GPU nodes use their GPU even where
// PoCL is installed beside it). The same rule picks among several devices that a substring matches,
// so "nvidia" on a node with many GPUs takes the first rather than refusing: P:D picks exactly.
//
// choose_device() is a pure function over records, so the matching is testable without OpenCL;
// enumerate_devices() builds the records from the OpenCL platforms.
#pragma once

#include <CL/cl.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace shadow::cl {

// Tests and benches, which build their device without a command line, read their SPEC here;
// the server's --device overrides it.
inline constexpr const char* kDeviceEnvironment = "SHADOW_DEVICE";

enum class DeviceType { kGpu, kCpu, kAccelerator, kOther };
const char* type_name(DeviceType type);  // "GPU", "CPU", "ACCELERATOR", "OTHER"

struct DeviceRecord {
  uint32_t platform_index = 0;
  uint32_t device_index = 0;  // within its platform
  std::string platform_name;
  std::string platform_vendor;
  std::string device_name;
  DeviceType type = DeviceType::kOther;
  std::string driver_version;
  std::string opencl_c_version;  // e.g. "OpenCL C 1.2 pocl"
  uint32_t compute_units = 0;
  uint64_t global_mem_bytes = 0;
  uint64_t max_alloc_bytes = 0;
};

// "P:D NAME (TYPE, PLATFORM, driver VERSION)": the start-up line and the candidates of an error.
std::string describe(const DeviceRecord& device);

// A SPEC that names no device (or a device list that is empty): a bad setting, not a failure of
// the device, so the server exits 2 for it as for other option errors.
class DeviceChoiceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A SPEC and the setting it came from, named in errors.
struct DeviceSpec {
  std::string text;  // empty: the default rule
  std::string setting;
};
// `flag` (the server's --device) when given, else $SHADOW_DEVICE, else no SPEC.
DeviceSpec resolve_device_spec(const std::string& flag);

// The index in `devices` that `spec` picks (see the top of this file). Throws DeviceChoiceError
// naming the setting and the SPEC, and listing every device, when it picks none.
size_t choose_device(const std::vector<DeviceRecord>& devices, const DeviceSpec& spec);

// Every platform and device the ICD loader offers, in its order. Throws cl::Error when there is
// no platform at all. A platform whose devices cannot be listed contributes none.
struct PlatformRecord {
  std::string name;
  std::string vendor;
  std::string version;  // e.g. "OpenCL 3.0 PoCL 5.0+debian ..."
};
struct Inventory {
  std::vector<PlatformRecord> platforms;  // by platform index
  std::vector<DeviceRecord> devices;
  std::vector<cl_device_id> ids;  // beside `devices`
};
Inventory enumerate_devices();

// --list-devices: each platform, then its devices with type, compute units, memory, largest
// buffer, OpenCL C version and driver; `chosen` (an index in `devices`) is marked.
std::string format_device_list(const std::vector<PlatformRecord>& platforms,
                               const std::vector<DeviceRecord>& devices,
                               std::optional<size_t> chosen);

}  // namespace shadow::cl
