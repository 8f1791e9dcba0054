#include "engine/passes/poisson_disk.hpp"

#include <cmath>
#include <random>

namespace shadow {

std::vector<glm::vec2> poisson_disk(uint32_t count) {
  std::mt19937 rng(count);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  // Start at the spacing of a hexagonal packing of `count` points and relax it whenever dart
  // throwing stalls, so every count finishes.
  float spacing = std::sqrt(3.14159265f / (count * 0.866f)) * 0.9f;
  std::vector<glm::vec2> points;
  int misses = 0;
  while (points.size() < count) {
    const glm::vec2 p(u(rng), u(rng));
    if (glm::dot(p, p) > 1.0f) continue;
    bool ok = true;
    for (const glm::vec2& q : points) ok = ok && glm::distance(p, q) >= spacing;
    if (ok) {
      points.push_back(p);
      misses = 0;
    } else if (++misses > 2000) {
      spacing *= 0.95f;
      misses = 0;
    }
  }
  return points;
}

}  // namespace shadow
