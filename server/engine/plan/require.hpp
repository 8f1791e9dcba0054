// The request checks' two primitives: a condition on a field, and an integer's range. Both throw
// InvalidArgument naming the field (wire/errors.hpp).
#pragma once

#include <cstdint>
#include <string>

#include "wire/errors.hpp"

namespace shadow {

inline void require(bool ok, const std::string& field, const std::string& why) {
  if (!ok) throw InvalidArgument(field, why);
}

inline void require_range(uint32_t v, uint32_t lo, uint32_t hi, const std::string& field) {
  require(
      v >= lo && v <= hi, field,
      "must be " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " + std::to_string(v));
}

}  // namespace shadow
