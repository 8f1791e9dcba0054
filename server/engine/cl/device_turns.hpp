// The device's time, shared fairly between clients (issue 51). Every launch slice takes a turn:
// one slice runs on the device at a time, so a slice's measured time is its own, and the next
// turn goes to the waiting client that has used the least device time, divided by its weight
// (weighted fair queuing on measured cost; first come first served among equals). A client's
// heavy work then delays another's small request by about one slice (Runtime::launch sizes
// slices to DeviceProfile::slice_ms), not by the length of its queue.
//
// A client that gives the device back while no waiting client has used less keeps it for up to
// kHoldMs: a request's launches come one after another with host work between them, and without
// the hold every one of them would wait a slice behind a heavy client that is always waiting
// (a small render's 30 launches waited 20 ms each under six heavy ones).
//
// Usage counts only while it can matter: a client that comes back after an idle spell starts no
// lower than the least-used client at work now (it cannot bank idle time) and at most
// kMemoryMs above it (old heavy use does not starve it for long).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <list>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace shadow::cl {

class DeviceTurns {
 public:
  // How far above the least-used active client a returning one may start, in weighted ms.
  static constexpr double kMemoryMs = 2000;
  // How long the device waits for the next launch of a client that is ahead.
  static constexpr std::chrono::microseconds kHold{2000};

  // Weights of named clients (tenants, or peers): a weight-2 client gets twice the device time of
  // a weight-1 one under contention. Others weigh 1.
  void set_weights(std::map<std::string, double> weights);

  // Waits until nothing runs on the device and no waiting client comes before `client`, then
  // holds the device for one command of `owner` (a queue, which has none running). Every take is
  // followed by exactly one give.
  void take(const std::string& client, const void* owner);
  // Without waiting: while one command of `owner` runs and no waiting client has used less,
  // queues a second behind it, so that the device does not idle between a queue's slices (a
  // slice that waited for the last to finish cost ~1 ms of PoCL's wake-ups). False otherwise:
  // the owner waits for its command, gives it back, then takes a turn as anyone does.
  bool take_behind(const std::string& client, const void* owner);
  // Gives the device back, charging `ms` of its time to `client`.
  void give(const std::string& client, double ms);

  // A client's weighted usage, as the next turn orders it (for admission's order between
  // waiting requests); a client not seen yet would start at the floor.
  double usage(const std::string& client);

  // Clients at work (admitted or waiting for admission): their usage is what orders turns; the
  // floor is the least usage among them. enter() counts one more piece of work, leave() one less.
  void enter(const std::string& client);
  void leave(const std::string& client);

  // Device ms each client has been charged since the start, the most used first (statistics).
  struct Total {
    std::string client;
    double ms = 0;
  };
  std::vector<Total> totals() const;

 private:
  struct Account {
    double usage = 0;  // weighted ms
    double total_ms = 0;
    uint32_t active = 0;   // pieces of work entered and not left
    uint32_t waiting = 0;  // turns asked for
  };
  // With the mutex held: the account, created at the floor; its weight.
  Account& account(const std::string& client);
  double weight(const std::string& client) const;
  double floor() const;  // the least usage of an active client, else the last such
  // With the mutex held: whether `ticket` of `client` is next.
  bool next(uint64_t ticket, const std::string& client);
  // With the mutex held: forgets idle clients past kMaxAccounts.
  void prune();
  static constexpr size_t kMaxAccounts = 4096;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  int running_ = 0;  // commands taken and not given back: at most kDepth, all of holder_'s
  const void* holder_ = nullptr;
  static constexpr int kDepth = 2;
  // The client the device is held for after it gave it back, and until when.
  std::string held_for_;
  std::chrono::steady_clock::time_point held_until_{};
  uint64_t next_ticket_ = 0;
  struct Waiter {
    uint64_t ticket;
    std::string client;
  };
  std::list<Waiter> waiting_;
  std::map<std::string, Account> accounts_;
  std::map<std::string, double> weights_;
  mutable double last_floor_ = 0;
};

}  // namespace shadow::cl
