#include "engine/cl/core_share.hpp"

#include <algorithm>
#include <fstream>
#include <string>

namespace shadow::cl {

void CoreShare::watch(std::set<pid_t> threads) {
  std::lock_guard lock(mutex_);
  threads_ = std::move(threads);
  last_ = read();
  sampled_ = std::chrono::steady_clock::now();
  share_ = 1;
}

CoreShare::Counters CoreShare::read() const {
  Counters sum;
  for (pid_t id : threads_) {
    // "<ns on a core> <ns waiting on a run queue> <time slices>"; a thread that ended reads
    // nothing.
    std::ifstream in("/proc/self/task/" + std::to_string(id) + "/schedstat");
    double run = 0, wait = 0;
    if (in >> run >> wait) sum.run_ns += run, sum.wait_ns += wait;
  }
  return sum;
}

double CoreShare::sample() const {
  std::lock_guard lock(mutex_);
  if (threads_.empty()) return 1;
  const auto now = std::chrono::steady_clock::now();
  if (now - sampled_ < kSampleEvery) return share_;
  const Counters now_counters = read();
  const double run = now_counters.run_ns - last_.run_ns;
  const double wait = now_counters.wait_ns - last_.wait_ns;
  if (run > 0 && wait >= 0) share_ = std::clamp(run / (run + wait), 1e-3, 1.0);
  last_ = now_counters;
  sampled_ = now;
  return share_;
}

}  // namespace shadow::cl
