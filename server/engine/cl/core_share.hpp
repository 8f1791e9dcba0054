// The share of a CPU device's time that its worker threads actually ran. PoCL runs kernels on
// host threads (at a lower priority: run/warm_up.hpp), so on a machine whose cores other
// processes share, a launch's measured time stretches with their load: a test suite running two
// tests at once stretched renders 3-7x, and two busy processes beside the server 10x. What a
// launch cost the device is its time times this share: the rest its threads waited for a core.
//
// Linux's per-thread schedstat gives each thread's time on a core and its time runnable but
// waiting for one; the share is their ratio over the threads, since the previous sample. With no
// threads watched (a GPU), or where the kernel does not count them, the share is 1.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <mutex>
#include <set>

namespace shadow::cl {

class CoreShare {
 public:
  // Samples closer together than this return the last share: reading a thread's counters costs
  // ~10 us, and a launch slice ~20 ms.
  static constexpr std::chrono::milliseconds kSampleEvery{50};

  // Watches these threads (a CPU device's workers) from now on.
  void watch(std::set<pid_t> threads);
  // The share, in (0, 1], of the watched threads' runnable time that they ran since the previous
  // sample; the last one while that was under kSampleEvery ago or they did not run.
  double sample() const;

 private:
  struct Counters {
    double run_ns = 0, wait_ns = 0;
  };
  Counters read() const;

  mutable std::mutex mutex_;
  std::set<pid_t> threads_;
  mutable Counters last_;
  mutable std::chrono::steady_clock::time_point sampled_;
  mutable double share_ = 1;
};

}  // namespace shadow::cl
