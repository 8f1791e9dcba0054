// The kernel profile (issue 42): the shape follows the device's type unless forced, the GPU
// shape's work-group is the largest power of two up to 256 that the device allows, launch slices
// grow with the compute units, and a choice that is no profile is refused by the setting's name.
// No OpenCL.
#include <gtest/gtest.h>

#include "engine/cl/device_profile.hpp"

namespace shadow::cl {
namespace {

DeviceRecord of_type(DeviceType type, uint32_t compute_units = 2) {
  DeviceRecord d;
  d.type = type;
  d.compute_units = compute_units;
  return d;
}

TEST(DeviceProfile, FollowsTheDeviceTypeUnlessForced) {
  EXPECT_EQ(make_profile(of_type(DeviceType::kGpu), 1024, "auto", "-").shape, KernelShape::kGpu);
  EXPECT_EQ(make_profile(of_type(DeviceType::kAccelerator), 1024, "", "-").shape,
            KernelShape::kGpu);
  EXPECT_EQ(make_profile(of_type(DeviceType::kCpu), 4096, "auto", "-").shape, KernelShape::kCpu);
  EXPECT_EQ(make_profile(of_type(DeviceType::kCpu), 4096, "gpu", "-").shape, KernelShape::kGpu);
  EXPECT_EQ(make_profile(of_type(DeviceType::kGpu), 1024, "cpu", "-").shape, KernelShape::kCpu);
}

TEST(DeviceProfile, GroupsSuitTheShape) {
  const DeviceProfile cpu = make_profile(of_type(DeviceType::kCpu), 4096, "cpu", "-");
  EXPECT_EQ(cpu.group_size, 1u);
  EXPECT_EQ(make_profile(of_type(DeviceType::kGpu), 1024, "gpu", "-").group_size, 256u);
  EXPECT_EQ(make_profile(of_type(DeviceType::kGpu), 192, "gpu", "-").group_size, 128u);
}

// A launch's first slice is one work-group per compute unit, whatever the device; later slices
// are sized by time (runtime_test's slicing tests).
TEST(DeviceProfile, FirstSlicesFillTheComputeUnits) {
  EXPECT_EQ(make_profile(of_type(DeviceType::kCpu, 128), 4096, "cpu", "-").first_slice_groups,
            128u);
  EXPECT_EQ(make_profile(of_type(DeviceType::kGpu, 132), 1024, "auto", "-").first_slice_groups,
            132u);
  // A device that reports no units is sliced as one unit.
  EXPECT_EQ(make_profile(of_type(DeviceType::kCpu, 0), 4096, "cpu", "-").first_slice_groups, 1u);
  EXPECT_GT(make_profile(of_type(DeviceType::kCpu, 2), 4096, "cpu", "-").slice_ms, 0);
}

TEST(DeviceProfile, AChoiceThatIsNoProfileIsRefusedByName) {
  try {
    make_profile(of_type(DeviceType::kCpu), 4096, "fast", "--kernel-profile");
    FAIL() << "accepted";
  } catch (const DeviceChoiceError& e) {
    EXPECT_NE(std::string(e.what()).find("--kernel-profile 'fast'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace shadow::cl
