// Who renders when: the engine's workspaces, the requests waiting for one and for their share of
// the memory budget, and the clients (tenants or peers) they belong to.
// - A request waits until a workspace is free and its pledge (its device buffers, with the
//   runtime's headroom) and its reply's bytes fit the budget.
// - The first in line is not the first to come but the waiter whose client has used the least
//   device time (cl::DeviceTurns' usage; first come first served among equals), and a client
//   that holds a workspace never takes the last free one (spare_workspace).
// - While the first in line waits for memory alone, requests behind it that fit now and whose
//   estimate is at most overtake_max_ms go first, during the first overtake_window_ms.
// - An engine with nothing running gives idle workspaces' scratch buffers back after a delay.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/runtime.hpp"
#include "engine/run/resident_scenes.hpp"
#include "engine/run/workspace.hpp"

namespace shadow {

// The EngineOptions the scheduler reads (engine/engine.hpp says what each does).
struct SchedulerOptions {
  uint32_t max_concurrent = 4;
  uint32_t max_queue = 16;
  double overtake_max_ms = 250;
  uint32_t overtake_window_ms = 1000;
  bool spare_workspace = true;
  uint64_t idle_memory_bytes = uint64_t{256} << 20;
  uint32_t idle_trim_delay_ms = 1000;
};

class Scheduler {
 public:
  static constexpr double kNoEstimate = std::numeric_limits<double>::infinity();

  Scheduler(const SchedulerOptions& options, std::shared_ptr<const cl::Device> device,
            cl::ProgramCache& programs, const ResidentScenes& resident);
  ~Scheduler();  // stops the idle trim
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  // One of the engine's workspaces, at start-up.
  void add(std::unique_ptr<Workspace> workspace);
  // Starts the idle trim (SchedulerOptions::idle_trim_delay_ms > 0), once the workspaces are in.
  void start();

  // What a request asks for.
  struct Ask {
    std::string client;
    std::function<bool()> cancelled;  // polled while it waits
    // Its held scene: the workspace that kept results for it is preferred.
    const Scene* scene = nullptr;
    uint64_t device_bytes = 0;  // the cost estimate's device buffers
    // A sequence between frames: the workspace that holds its state, if still idle.
    uint64_t sequence = 0;
    // With `reply`, `reply_bytes` are reserved there with the pledge, under the same wait.
    cl::Reservation* reply = nullptr;
    uint64_t reply_bytes = 0;
    // Its cost estimate, for going before one that waits for memory; kNoEstimate for none.
    double estimated_ms = kNoEstimate;
  };

  // A workspace held by one request; back to the idle set when the lease ends.
  class Lease {
   public:
    Lease(Scheduler& scheduler, std::unique_ptr<Workspace> workspace, std::string client)
        : scheduler_(&scheduler), workspace_(std::move(workspace)), client_(std::move(client)) {}
    Lease(Lease&&) = default;
    Lease& operator=(Lease&&) = delete;
    ~Lease() { release(); }
    Workspace* operator->() const { return workspace_.get(); }
    // Gives the workspace back now.
    void release() {
      if (workspace_) scheduler_->release(std::move(workspace_), client_);
    }

   private:
    Scheduler* scheduler_;
    std::unique_ptr<Workspace> workspace_;
    std::string client_;
  };

  // Waits for a workspace and the request's share of the budget. Picks the workspace that kept
  // its last results for `ask.scene` (or `ask.sequence`) if free, else one that kept none and
  // holds no sequence, else the one idle longest; whoever gets a workspace holding another
  // sequence's state ends it. Throws ResourceExhausted when the queue is full, or when the
  // buffers do not fit even with nothing rendering and every idle workspace emptied (the budget
  // is held by replies, uploads and waiting requests); Cancelled once `ask.cancelled` says so.
  Lease acquire(const Ask& ask);

  // A client's work, from admission to its end: its device usage orders turns and admission
  // while it lasts (cl::DeviceTurns::enter).
  class AtWork {
   public:
    AtWork(Scheduler& scheduler, std::string client);
    ~AtWork();
    AtWork(const AtWork&) = delete;
    AtWork& operator=(const AtWork&) = delete;

   private:
    cl::DeviceTurns& turns_;
    std::string client_;
  };

  struct Load {
    uint32_t rendering = 0, workspaces = 0, waiting = 0;
  };
  Load load() const;

 private:
  void release(std::unique_ptr<Workspace> workspace, const std::string& client);
  // With the mutex held: whether `client` may take a free workspace now (the spare one is for a
  // client that holds none).
  bool may_take(const std::string& client) const;
  // With the mutex held: the ticket of the waiter that goes next when a workspace is free, among
  // those that may take one; none if none may.
  std::optional<uint64_t> first_in_line() const;
  // With the mutex held: whether waiter `ticket` may go before the first in line, which waits
  // for memory alone (a workspace is free) and has done so for less than the window.
  bool may_overtake(uint64_t ticket, double estimated_ms) const;
  // A request's share of the budget: the pledge for its device buffers and its reply's bytes.
  struct Share {
    cl::Reservation pledge, reply;
  };
  // That share, if free now.
  std::optional<Share> share(uint64_t device_bytes, uint64_t reply_bytes);
  // With the mutex held: if nothing runs or waits and more than idle_memory_bytes are in use,
  // empty_idle(spare).
  std::vector<std::unique_ptr<Workspace>> trim(const Workspace* spare);
  // With the mutex held: every idle workspace but `spare` (when it keeps a held scene's results)
  // starts over empty; the emptied ones are returned, to be destroyed outside the lock.
  std::vector<std::unique_ptr<Workspace>> empty_idle(const Workspace* spare);
  // The trimming thread's loop (idle_trim_delay_ms > 0): trims once trim_at_ has passed.
  void trim_when_due();

  const SchedulerOptions options_;
  const std::shared_ptr<const cl::Device> device_;
  cl::ProgramCache& programs_;
  const ResidentScenes& resident_;
  mutable std::mutex mutex_;
  std::condition_variable freed_;
  std::vector<std::unique_ptr<Workspace>> idle_;  // workspaces no request holds
  struct Waiter {
    uint64_t ticket;
    std::string client;
  };
  std::deque<Waiter> waiting_;               // the requests waiting, in the order they came
  std::map<std::string, uint32_t> holding_;  // workspaces each client holds
  uint64_t next_ticket_ = 0;
  // The first in line's ticket and since when it has found a workspace free but not its memory.
  std::optional<std::pair<uint64_t, std::chrono::steady_clock::time_point>> short_of_memory_;
  // When to trim: set as the last request ends (the trim then checks the memory), reset when one
  // starts.
  std::optional<std::chrono::steady_clock::time_point> trim_at_;
  const Workspace* trim_spare_ = nullptr;  // the workspace released last
  bool stopping_ = false;
  std::condition_variable trim_wake_;
  std::thread trimmer_;  // runs trim_when_due
};

}  // namespace shadow
