#include "service/stall_watchdog.hpp"

#include <algorithm>

namespace shadow::service {

StallWatchdog::StallWatchdog(std::chrono::milliseconds timeout)
    : timeout_(timeout), thread_([this] { run(); }) {}

StallWatchdog::~StallWatchdog() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  stop_.notify_all();
  thread_.join();
}

void StallWatchdog::run() {
  const auto period =
      std::clamp(timeout_ / 4, std::chrono::milliseconds(10), std::chrono::milliseconds(1000));
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_.wait_for(lock, period, [this] { return stopping_; })) {
    const Clock::time_point now = Clock::now();
    for (Watch::Entry& e : calls_) {
      if (!e.stalled && now - e.last > timeout_) {
        e.stalled = true;
        e.context->TryCancel();  // the blocked Write or Read returns false
      }
    }
  }
}

StallWatchdog::Watch::Watch(StallWatchdog& dog, grpc::ServerContext* context) : dog_(dog) {
  std::lock_guard<std::mutex> lock(dog_.mutex_);
  entry_ = dog_.calls_.insert(dog_.calls_.end(), Entry{context, Clock::now()});
}

StallWatchdog::Watch::~Watch() {
  std::lock_guard<std::mutex> lock(dog_.mutex_);
  dog_.calls_.erase(entry_);
}

void StallWatchdog::Watch::progress() {
  std::lock_guard<std::mutex> lock(dog_.mutex_);
  entry_->last = Clock::now();
}

bool StallWatchdog::Watch::stalled() const {
  std::lock_guard<std::mutex> lock(dog_.mutex_);
  return entry_->stalled;
}

}  // namespace shadow::service
