// A chunked parallel loop over all hardware threads, for the oracle's per-point work.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace shadow::oracle {

// Runs fn(begin, end) over [0, count) on all hardware threads, in chunks so that rows of
// uneven cost balance out.
template <typename Fn>
void parallel_for(size_t count, Fn fn) {
  const size_t threads = std::max(1u, std::thread::hardware_concurrency());
  const size_t chunk = std::max<size_t>(1, std::min<size_t>(4096, count / (threads * 16) + 1));
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t begin; (begin = next.fetch_add(chunk)) < count;) {
      fn(begin, std::min(count, begin + chunk));
    }
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace shadow::oracle
