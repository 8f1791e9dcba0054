#include "engine/cl/device_choice.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>

#include "engine/cl/runtime.hpp"

namespace shadow::cl {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// "P:D" with both parts decimal; nullopt for anything else (then the SPEC is a name).
std::optional<std::pair<uint64_t, uint64_t>> parse_index(const std::string& spec) {
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) return std::nullopt;
  const std::string p = spec.substr(0, colon), d = spec.substr(colon + 1);
  const auto decimal = [](const std::string& s) {
    return !s.empty() && s.size() <= 9 &&
           std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  if (!decimal(p) || !decimal(d)) return std::nullopt;
  return std::make_pair(std::stoull(p), std::stoull(d));
}

// The default rule over `candidates` (indices in `devices`, non-empty).
size_t preferred(const std::vector<DeviceRecord>& devices, const std::vector<size_t>& candidates) {
  for (DeviceType type : {DeviceType::kGpu, DeviceType::kCpu})
    for (size_t i : candidates)
      if (devices[i].type == type) return i;
  return candidates.front();
}

[[noreturn]] void refuse(const std::vector<DeviceRecord>& devices, const DeviceSpec& spec,
                         const std::string& why) {
  std::string message =
      spec.setting + " '" + spec.text + "' names no OpenCL device: " + why +
      " (a SPEC is P:D or part of a platform's name or vendor or of a device's name, any "
      "case); ";
  if (devices.empty()) {
    message += "there is no OpenCL device";
  } else {
    message += "the devices are:";
    for (const DeviceRecord& d : devices) message += "\n  " + describe(d);
  }
  throw DeviceChoiceError(message);
}

std::string platform_string(cl_platform_id p, cl_platform_info what) {
  size_t n = 0;
  if (clGetPlatformInfo(p, what, 0, nullptr, &n) != CL_SUCCESS) return {};
  std::string s(n, '\0');
  if (clGetPlatformInfo(p, what, n, s.data(), nullptr) != CL_SUCCESS) return {};
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

std::string device_string(cl_device_id d, cl_device_info what) {
  size_t n = 0;
  check(clGetDeviceInfo(d, what, 0, nullptr, &n), "clGetDeviceInfo");
  std::string s(n, '\0');
  check(clGetDeviceInfo(d, what, n, s.data(), nullptr), "clGetDeviceInfo");
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

template <typename T>
T device_value(cl_device_id d, cl_device_info what) {
  T value{};
  check(clGetDeviceInfo(d, what, sizeof(T), &value, nullptr), "clGetDeviceInfo");
  return value;
}

DeviceType classify(cl_device_type type) {
  if (type & CL_DEVICE_TYPE_GPU) return DeviceType::kGpu;
  if (type & CL_DEVICE_TYPE_CPU) return DeviceType::kCpu;
  if (type & CL_DEVICE_TYPE_ACCELERATOR) return DeviceType::kAccelerator;
  return DeviceType::kOther;
}

std::string bytes_text(uint64_t bytes) {
  char text[32];
  if (bytes >= (uint64_t{1} << 30))
    std::snprintf(text, sizeof text, "%.1f GiB", double(bytes) / double(uint64_t{1} << 30));
  else
    std::snprintf(text, sizeof text, "%.0f MiB", double(bytes) / double(uint64_t{1} << 20));
  return text;
}

}  // namespace

const char* type_name(DeviceType type) {
  switch (type) {
    case DeviceType::kGpu:
      return "GPU";
    case DeviceType::kCpu:
      return "CPU";
    case DeviceType::kAccelerator:
      return "ACCELERATOR";
    case DeviceType::kOther:
      break;
  }
  return "OTHER";
}

std::string describe(const DeviceRecord& d) {
  return std::to_string(d.platform_index) + ":" + std::to_string(d.device_index) + " " +
         d.device_name + " (" + type_name(d.type) + ", " + d.platform_name + ", driver " +
         d.driver_version + ")";
}

DeviceSpec resolve_device_spec(const std::string& flag) {
  if (!flag.empty()) return {flag, "--device"};
  if (const char* env = std::getenv(kDeviceEnvironment); env && *env)
    return {env, kDeviceEnvironment};
  return {};
}

size_t choose_device(const std::vector<DeviceRecord>& devices, const DeviceSpec& spec) {
  if (spec.text.empty()) {
    if (devices.empty()) throw DeviceChoiceError("there is no OpenCL device");
    std::vector<size_t> all(devices.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
    return preferred(devices, all);
  }
  if (const auto index = parse_index(spec.text)) {
    for (size_t i = 0; i < devices.size(); ++i)
      if (devices[i].platform_index == index->first && devices[i].device_index == index->second)
        return i;
    refuse(devices, spec,
           "there is no device " + std::to_string(index->second) + " on platform " +
               std::to_string(index->first));
  }
  const std::string part = lower(spec.text);
  std::vector<size_t> matches;
  for (size_t i = 0; i < devices.size(); ++i)
    for (const std::string* name :
         {&devices[i].platform_name, &devices[i].platform_vendor, &devices[i].device_name})
      if (lower(*name).find(part) != std::string::npos) {
        matches.push_back(i);
        break;
      }
  if (matches.empty())
    refuse(devices, spec, "no platform name or vendor and no device name contains it");
  return preferred(devices, matches);
}

Inventory enumerate_devices() {
  cl_uint count = 0;
  const cl_int err = clGetPlatformIDs(0, nullptr, &count);
  // The ICD loader answers -1001 (CL_PLATFORM_NOT_FOUND_KHR) when no driver is registered.
  if (count == 0)
    throw Error(
        "clGetPlatformIDs (no OpenCL platform; is an OpenCL driver such as "
        "pocl-opencl-icd installed?)",
        err != CL_SUCCESS ? err : CL_DEVICE_NOT_FOUND);
  std::vector<cl_platform_id> platforms(count);
  check(clGetPlatformIDs(count, platforms.data(), nullptr), "clGetPlatformIDs");

  Inventory inventory;
  for (cl_uint p = 0; p < count; ++p) {
    inventory.platforms.push_back({platform_string(platforms[p], CL_PLATFORM_NAME),
                                   platform_string(platforms[p], CL_PLATFORM_VENDOR),
                                   platform_string(platforms[p], CL_PLATFORM_VERSION)});
    cl_uint n = 0;
    if (clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, 0, nullptr, &n) != CL_SUCCESS || n == 0)
      continue;
    std::vector<cl_device_id> ids(n);
    if (clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, n, ids.data(), nullptr) != CL_SUCCESS)
      continue;
    for (cl_uint d = 0; d < n; ++d) {
      DeviceRecord r;
      r.platform_index = p;
      r.device_index = d;
      r.platform_name = inventory.platforms.back().name;
      r.platform_vendor = inventory.platforms.back().vendor;
      r.device_name = device_string(ids[d], CL_DEVICE_NAME);
      r.type = classify(device_value<cl_device_type>(ids[d], CL_DEVICE_TYPE));
      r.driver_version = device_string(ids[d], CL_DRIVER_VERSION);
      r.opencl_c_version = device_string(ids[d], CL_DEVICE_OPENCL_C_VERSION);
      r.compute_units = device_value<cl_uint>(ids[d], CL_DEVICE_MAX_COMPUTE_UNITS);
      r.global_mem_bytes = device_value<cl_ulong>(ids[d], CL_DEVICE_GLOBAL_MEM_SIZE);
      r.max_alloc_bytes = device_value<cl_ulong>(ids[d], CL_DEVICE_MAX_MEM_ALLOC_SIZE);
      inventory.devices.push_back(std::move(r));
      inventory.ids.push_back(ids[d]);
    }
  }
  return inventory;
}

std::string format_device_list(const std::vector<PlatformRecord>& platforms,
                               const std::vector<DeviceRecord>& devices,
                               std::optional<size_t> chosen) {
  std::string out;
  for (size_t p = 0; p < platforms.size(); ++p) {
    out += "platform " + std::to_string(p) + ": " + platforms[p].name + " (" + platforms[p].vendor +
           "; " + platforms[p].version + ")\n";
    bool any = false;
    for (size_t i = 0; i < devices.size(); ++i) {
      const DeviceRecord& d = devices[i];
      if (d.platform_index != p) continue;
      any = true;
      out += "  " + std::to_string(d.platform_index) + ":" + std::to_string(d.device_index) + " " +
             type_name(d.type) + " " + d.device_name + (chosen == i ? "  [chosen]" : "") +
             "\n      " + std::to_string(d.compute_units) + " compute units, " +
             bytes_text(d.global_mem_bytes) + " global memory, " + bytes_text(d.max_alloc_bytes) +
             " max buffer, " + d.opencl_c_version + ", driver " + d.driver_version + "\n";
    }
    if (!any) out += "  (no devices)\n";
  }
  return out;
}

}  // namespace shadow::cl
