// Device choice (issue 41) over synthetic device lists: no OpenCL device is touched.
#include <gmock/gmock.h>

#include <cstdlib>

#include "engine/cl/device_choice.hpp"

namespace shadow::cl {
namespace {

using ::testing::HasSubstr;

DeviceRecord record(uint32_t p, uint32_t d, std::string platform, std::string name, DeviceType type,
                    std::string vendor = "") {
  DeviceRecord r;
  r.platform_index = p;
  r.device_index = d;
  r.platform_name = std::move(platform);
  r.platform_vendor = std::move(vendor);
  r.device_name = std::move(name);
  r.type = type;
  r.driver_version = "1.0";
  r.opencl_c_version = "OpenCL C 1.2";
  r.compute_units = 8;
  r.global_mem_bytes = uint64_t{16} << 30;
  r.max_alloc_bytes = uint64_t{4} << 30;
  return r;
}

// A farm node as the issue found it: PoCL registered first, two GPUs after it.
const std::vector<DeviceRecord> kFarmNode = {
    record(0, 0, "Portable Computing Language", "cpu-haswell-AMD EPYC 9654", DeviceType::kCpu,
           "The pocl project"),
    record(1, 0, "NVIDIA CUDA", "NVIDIA H200", DeviceType::kGpu, "NVIDIA Corporation"),
    record(1, 1, "NVIDIA CUDA", "NVIDIA H200", DeviceType::kGpu, "NVIDIA Corporation"),
};

size_t choose(const std::vector<DeviceRecord>& devices, const std::string& spec) {
  return choose_device(devices, {spec, "--device"});
}

std::string refusal(const std::vector<DeviceRecord>& devices, const std::string& spec) {
  try {
    choose(devices, spec);
  } catch (const DeviceChoiceError& e) {
    return e.what();
  }
  ADD_FAILURE() << "'" << spec << "' was taken";
  return {};
}

TEST(DeviceChoice, DefaultPrefersAGpuThenACpuThenTheFirst) {
  EXPECT_EQ(choose(kFarmNode, ""), 1u);
  const std::vector<DeviceRecord> no_gpu = {
      record(0, 0, "Accel", "fpga", DeviceType::kAccelerator),
      record(1, 0, "Portable Computing Language", "cpu", DeviceType::kCpu)};
  EXPECT_EQ(choose(no_gpu, ""), 1u);
  const std::vector<DeviceRecord> neither = {
      record(0, 0, "Accel", "fpga", DeviceType::kAccelerator),
      record(0, 1, "Accel", "dsp", DeviceType::kOther)};
  EXPECT_EQ(choose(neither, ""), 0u);
}

TEST(DeviceChoice, APartOfAPlatformNameOrVendorOrADeviceNameInAnyCase) {
  EXPECT_EQ(choose(kFarmNode, "pocl"), 0u);  // the platform's vendor
  EXPECT_EQ(choose(kFarmNode, "portable"), 0u);
  EXPECT_EQ(choose(kFarmNode, "COMPUTING language"), 0u);
  EXPECT_EQ(choose(kFarmNode, "epyc"), 0u);  // the device's name
  EXPECT_EQ(choose(kFarmNode, "nvidia"), 1u);
  EXPECT_EQ(choose(kFarmNode, "h200"), 1u);
  EXPECT_EQ(choose(kFarmNode, "Cuda"), 1u);
  EXPECT_EQ(choose(kFarmNode, "corporation"), 1u);
}

// Several matches: the default rule among them, so "nvidia" on a many-GPU node takes the first
// GPU, and a name shared by a CPU and a GPU platform takes the GPU.
TEST(DeviceChoice, AnAmbiguousSubstringPicksAsTheDefaultDoesAmongItsMatches) {
  EXPECT_EQ(choose(kFarmNode, "NVIDIA"), 1u);
  const std::vector<DeviceRecord> intel = {
      record(0, 0, "Intel(R) OpenCL", "Intel(R) Xeon(R)", DeviceType::kCpu),
      record(1, 0, "Intel(R) OpenCL Graphics", "Intel(R) Arc(TM) A770", DeviceType::kGpu)};
  EXPECT_EQ(choose(intel, "intel"), 1u);
  EXPECT_EQ(choose(intel, "xeon"), 0u);
}

TEST(DeviceChoice, PlatformColonDevicePicksExactly) {
  EXPECT_EQ(choose(kFarmNode, "0:0"), 0u);
  EXPECT_EQ(choose(kFarmNode, "1:0"), 1u);
  EXPECT_EQ(choose(kFarmNode, "1:1"), 2u);
  EXPECT_EQ(choose(kFarmNode, "01:1"), 2u);
}

TEST(DeviceChoice, AnIndexOutOfRangeIsRefusedNamingIt) {
  for (const char* spec : {"2:0", "0:1", "1:2", "999999999:0"}) {
    const std::string message = refusal(kFarmNode, spec);
    EXPECT_THAT(message, HasSubstr(std::string("--device '") + spec + "' names no OpenCL device"));
    EXPECT_THAT(message, HasSubstr("there is no device"));
  }
}

TEST(DeviceChoice, NoMatchListsEveryDevice) {
  const std::string message = refusal(kFarmNode, "nothing-like-this");
  EXPECT_THAT(message, HasSubstr("--device 'nothing-like-this' names no OpenCL device"));
  EXPECT_THAT(message,
              HasSubstr("\n  0:0 cpu-haswell-AMD EPYC 9654 (CPU, Portable Computing Language, "
                        "driver 1.0)"));
  EXPECT_THAT(message, HasSubstr("\n  1:0 NVIDIA H200 (GPU, NVIDIA CUDA, driver 1.0)"));
  EXPECT_THAT(message, HasSubstr("\n  1:1 NVIDIA H200 (GPU"));
  // Not an index: a name (that matches nothing).
  EXPECT_THAT(refusal(kFarmNode, "1:x"),
              HasSubstr("no platform name or vendor and no device name contains it"));
  EXPECT_THAT(refusal({}, "pocl"), HasSubstr("there is no OpenCL device"));
  EXPECT_THROW(choose({}, ""), DeviceChoiceError);
}

TEST(DeviceChoice, TheFlagOverridesTheEnvironment) {
  const char* saved = std::getenv(kDeviceEnvironment);
  const std::string restore = saved ? saved : "";
  setenv(kDeviceEnvironment, "nvidia", 1);
  const DeviceSpec from_env = resolve_device_spec("");
  EXPECT_EQ(from_env.text, "nvidia");
  EXPECT_EQ(from_env.setting, "SHADOW_DEVICE");
  EXPECT_THAT(refusal(kFarmNode, "x"), HasSubstr("--device 'x'"));
  try {
    choose_device(kFarmNode, {"intel", kDeviceEnvironment});
    ADD_FAILURE();
  } catch (const DeviceChoiceError& e) {
    EXPECT_THAT(e.what(), HasSubstr("SHADOW_DEVICE 'intel' names no OpenCL device"));
  }
  const DeviceSpec from_flag = resolve_device_spec("0:0");
  EXPECT_EQ(from_flag.text, "0:0");
  EXPECT_EQ(from_flag.setting, "--device");
  unsetenv(kDeviceEnvironment);
  EXPECT_EQ(resolve_device_spec("").text, "");
  if (saved) setenv(kDeviceEnvironment, restore.c_str(), 1);
}

TEST(DeviceChoice, TheListShowsEveryPlatformAndMarksTheChoice) {
  const std::string list =
      format_device_list({{"Portable Computing Language", "The pocl project", "OpenCL 3.0 PoCL"},
                          {"NVIDIA CUDA", "NVIDIA Corporation", "OpenCL 3.0 CUDA 13.0.94"},
                          {"Empty", "Nobody", "OpenCL 1.2"}},
                         kFarmNode, 1);
  EXPECT_THAT(list, HasSubstr("platform 0: Portable Computing Language (The pocl project; OpenCL "
                              "3.0 PoCL)\n  0:0 CPU "
                              "cpu-haswell-AMD EPYC 9654\n      8 compute units, 16.0 GiB global "
                              "memory, 4.0 GiB max buffer, OpenCL C 1.2, driver 1.0\n"));
  EXPECT_THAT(list, HasSubstr("  1:0 GPU NVIDIA H200  [chosen]\n"));
  EXPECT_THAT(list, HasSubstr("  1:1 GPU NVIDIA H200\n"));
  EXPECT_THAT(list, HasSubstr("platform 2: Empty (Nobody; OpenCL 1.2)\n  (no devices)\n"));
}

}  // namespace
}  // namespace shadow::cl
