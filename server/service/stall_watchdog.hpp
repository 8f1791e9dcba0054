// Cancels calls whose peer makes no progress. In gRPC's synchronous API a Write blocks until the
// peer reads (flow control), so a client that stops reading would hold its reply, and the
// memory reserved for it, for ever; a Read blocks until the peer writes, so a client that stops
// sending an upload would hold its tenant slot and what it sent so far. Cancelling the call
// makes the blocked Write or Read return false. One thread checks every watched call a few
// times per timeout.
#pragma once

#include <chrono>
#include <condition_variable>
#include <list>
#include <mutex>
#include <thread>

#include <grpcpp/server_context.h>

namespace shadow::service {

class StallWatchdog {
 public:
  using Clock = std::chrono::steady_clock;

  explicit StallWatchdog(std::chrono::milliseconds timeout);
  ~StallWatchdog();
  StallWatchdog(const StallWatchdog&) = delete;
  StallWatchdog& operator=(const StallWatchdog&) = delete;

  // Watches one call from now until it goes; progress() after every message the peer took (a
  // Write) or sent (a Read).
  class Watch {
   public:
    Watch(StallWatchdog& dog, grpc::ServerContext* context);
    ~Watch();
    Watch(const Watch&) = delete;
    Watch& operator=(const Watch&) = delete;
    void progress();
    bool stalled() const;  // the watchdog cancelled the call

   private:
    struct Entry {
      grpc::ServerContext* context;
      Clock::time_point last;
      bool stalled = false;
    };
    friend class StallWatchdog;
    StallWatchdog& dog_;
    std::list<Entry>::iterator entry_;
  };

 private:
  void run();

  const std::chrono::milliseconds timeout_;
  mutable std::mutex mutex_;
  std::condition_variable stop_;
  bool stopping_ = false;
  std::list<Watch::Entry> calls_;
  std::thread thread_;
};

}  // namespace shadow::service
