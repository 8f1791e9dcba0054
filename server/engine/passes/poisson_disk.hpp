// Poisson-disk tap patterns in the unit disk for PCF: deterministic, well spread for any count.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace shadow {

// `count` points (1..64) in the unit disk, no two closer than the largest spacing that dart
// throwing with a fixed seed reaches; the same count always gives the same pattern.
std::vector<glm::vec2> poisson_disk(uint32_t count);

}  // namespace shadow
