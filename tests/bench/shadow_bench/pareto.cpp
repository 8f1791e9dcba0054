#include "pareto.hpp"

#include <cstddef>

namespace shadow::bench {

std::vector<bool> pareto_front(const std::vector<double>& time, const std::vector<double>& error) {
  std::vector<bool> front(time.size(), true);
  for (size_t i = 0; i < time.size(); ++i) {
    for (size_t j = 0; j < time.size(); ++j) {
      const bool no_worse = time[j] <= time[i] && error[j] <= error[i];
      const bool better = time[j] < time[i] || error[j] < error[i];
      if (j != i && no_worse && better) {
        front[i] = false;
        break;
      }
    }
  }
  return front;
}

}  // namespace shadow::bench
