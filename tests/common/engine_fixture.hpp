// Engines and devices the tests share, per test binary, built on first use (an engine's start-up
// builds and warms every kernel, seconds on PoCL).
// - engine(): the one Engine, with the default options, that every test needing one shares.
//   Tests that need other options (budgets, calibrations, queues) build their own.
// - engine(profile): one engine per kernel profile ("cpu", "gpu"), one workspace each: the tests
//   that hold the two shapes to the same bits render on both.
// - ProfileDevice: a device of its own forced to one kernel profile, for tests of single passes.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/runtime.hpp"
#include "engine/engine.hpp"

namespace shadow::testing {

inline Engine& engine() {
  static Engine e;
  return e;
}

inline Engine& engine(const std::string& kernel_profile) {
  static std::map<std::string, std::unique_ptr<Engine>> engines;
  std::unique_ptr<Engine>& e = engines[kernel_profile];
  if (!e) {
    EngineOptions o;
    o.kernel_profile = kernel_profile;
    o.max_concurrent = 1;
    e = std::make_unique<Engine>(o);
  }
  return *e;
}

// Its own context, so each profile's device gets its own copies of the inputs.
struct ProfileDevice {
  explicit ProfileDevice(const std::string& profile)
      : runtime(std::make_shared<cl::Device>(0, std::string(), profile)) {}
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};

  template <typename T = float>
  std::vector<T> read(const cl::Buffer& b, size_t count) {
    std::vector<T> out(count);
    if (count) runtime.read(b, out.data(), count * sizeof(T));
    return out;
  }
};

}  // namespace shadow::testing
