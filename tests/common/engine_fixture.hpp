// The one Engine that every test needing a default engine shares, per test binary: built on first
// use (its start-up builds and warms every kernel, seconds on PoCL), with the default options.
// Tests that need other options (budgets, calibrations, queues) build their own.
#pragma once

#include "engine/engine.hpp"

namespace shadow::testing {

inline Engine& engine() {
  static Engine e;
  return e;
}

}  // namespace shadow::testing
