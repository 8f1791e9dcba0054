// CoreShare: the share of their runnable time that watched threads ran, from Linux's per-thread
// schedstat. Three threads spin on one core: the watched one runs about a third of the time.
#include "engine/cl/core_share.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <thread>
#include <vector>

namespace shadow::cl {
namespace {

bool counted_here() {
  std::ifstream in("/proc/self/schedstat");
  double run = 0;
  return bool(in >> run);
}

TEST(CoreShare, IsOneWithNothingWatched) {
  CoreShare share;
  EXPECT_EQ(share.sample(), 1.0);
  share.watch({});
  std::this_thread::sleep_for(CoreShare::kSampleEvery * 2);
  EXPECT_EQ(share.sample(), 1.0);
}

TEST(CoreShare, ThreadsThatShareACoreRunPartOfTheTime) {
  if (!counted_here()) GTEST_SKIP() << "this kernel does not count threads' run queue time";
  std::atomic<bool> stop{false};
  std::atomic<pid_t> watched{0};
  std::vector<std::thread> spinners;
  for (int i = 0; i < 3; ++i)
    spinners.emplace_back([&, i] {
      cpu_set_t one;
      CPU_ZERO(&one);
      CPU_SET(0, &one);
      pthread_setaffinity_np(pthread_self(), sizeof one, &one);
      if (i == 0) watched = pid_t(syscall(SYS_gettid));
      while (!stop.load(std::memory_order_relaxed)) {
      }
    });
  while (watched == 0) std::this_thread::yield();
  CoreShare share;
  share.watch({watched.load()});
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  const double ran = share.sample();
  // A sample sooner than kSampleEvery returns the same share.
  EXPECT_EQ(share.sample(), ran);
  stop = true;
  for (std::thread& t : spinners) t.join();
  // A third, less whatever else this machine runs on that core; never more than about half.
  EXPECT_GT(ran, 0.0);
  EXPECT_LT(ran, 0.55) << "three threads on one core";
}

}  // namespace
}  // namespace shadow::cl
