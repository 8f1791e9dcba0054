// The memory floor of a pass: bytes it must move over this machine's streaming bandwidth,
// measured here (2 threads copying 2 x 128 MiB with memcpy, best of 5; read + write bytes).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstring>
#include <thread>
#include <vector>

namespace shadow::bench {

inline double stream_bytes_per_s() {
  static const double measured = [] {
    const size_t half = size_t{128} << 20;
    std::vector<char> src(2 * half, 1), dst(2 * half, 0);
    double best = 0;
    for (int rep = 0; rep < 5; ++rep) {
      const auto start = std::chrono::steady_clock::now();
      std::thread t([&] { std::memcpy(dst.data(), src.data(), half); });
      std::memcpy(dst.data() + half, src.data() + half, half);
      t.join();
      const double s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      best = std::max(best, 2.0 * 2 * half / s);
    }
    return best;
  }();
  return measured;
}

// Milliseconds to move `bytes` at the measured bandwidth.
inline double floor_ms(double bytes) {
  return bytes / stream_bytes_per_s() * 1e3;
}

}  // namespace shadow::bench
