#include "engine/run/scheduler.hpp"

#include <algorithm>
#include <iostream>

#include "engine/choose/price.hpp"
#include "wire/errors.hpp"

namespace shadow {

Scheduler::Scheduler(const SchedulerOptions& options, std::shared_ptr<const cl::Device> device,
                     cl::ProgramCache& programs, const ResidentScenes& resident)
    : options_(options), device_(std::move(device)), programs_(programs), resident_(resident) {}

void Scheduler::start() {
  if (options_.idle_trim_delay_ms > 0 && !trimmer_.joinable())
    trimmer_ = std::thread([this] { trim_when_due(); });
}

Scheduler::~Scheduler() {
  if (!trimmer_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  trim_wake_.notify_one();
  trimmer_.join();
}

void Scheduler::add(std::unique_ptr<Workspace> workspace) {
  std::lock_guard<std::mutex> lock(mutex_);
  idle_.push_back(std::move(workspace));
}

Scheduler::AtWork::AtWork(Scheduler& scheduler, std::string client)
    : turns_(scheduler.device_->turns()), client_(std::move(client)) {
  turns_.enter(client_);
}

Scheduler::AtWork::~AtWork() {
  turns_.leave(client_);
}

Scheduler::Load Scheduler::load() const {
  std::lock_guard<std::mutex> lock(mutex_);
  const uint32_t all = options_.max_concurrent;
  return {all - std::min<uint32_t>(all, uint32_t(idle_.size())), all, uint32_t(waiting_.size())};
}

std::vector<std::unique_ptr<Workspace>> Scheduler::trim(const Workspace* spare) {
  if (idle_.size() != options_.max_concurrent || !waiting_.empty() ||
      device_->allocated_bytes() <= options_.idle_memory_bytes + resident_.bytes())
    return {};
  return empty_idle(spare);
}

std::vector<std::unique_ptr<Workspace>> Scheduler::empty_idle(const Workspace* spare) {
  std::vector<std::unique_ptr<Workspace>> emptied;
  for (std::unique_ptr<Workspace>& w : idle_) {
    if (w.get() == spare && (w->warm_scene() || w->sequence())) continue;
    // A fresh workspace takes a few bytes of the budget; when even those are not free (uploads
    // and replies can hold it all), this workspace keeps its buffers: a trim is only a saving.
    std::unique_ptr<Workspace> fresh;
    try {
      fresh = std::make_unique<Workspace>(device_, programs_);
    } catch (const std::exception&) {
      break;
    }
    emptied.push_back(std::exchange(w, std::move(fresh)));
  }
  return emptied;
}

void Scheduler::trim_when_due() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_) {
    if (!trim_at_) {
      trim_wake_.wait(lock);
    } else if (std::chrono::steady_clock::now() < *trim_at_) {
      trim_wake_.wait_until(lock, *trim_at_);
    } else {
      trim_at_.reset();
      std::vector<std::unique_ptr<Workspace>> emptied;
      try {
        emptied = trim(trim_spare_);
      } catch (const std::exception& e) {
        // Nothing may escape this thread (std::terminate would end every request); a trim is
        // only a saving, so the next one tries again.
        std::cerr << "shadow-engine: the idle trim failed: " << e.what() << '\n';
      }
      lock.unlock();
      emptied.clear();  // their buffers go back outside the lock
      lock.lock();
    }
  }
}

std::optional<Scheduler::Share> Scheduler::share(uint64_t device_bytes, uint64_t reply_bytes) {
  try {
    Share s;
    s.pledge = device_->reserve(pledged_bytes(device_bytes, device_->budget_bytes()),
                                "request's device buffers");
    s.reply = device_->reserve(reply_bytes, "reply");
    return s;
  } catch (const ResourceExhausted&) {
    return std::nullopt;  // what was reserved goes back
  }
}

bool Scheduler::may_take(const std::string& client) const {
  if (!options_.spare_workspace || options_.max_concurrent == 1 || idle_.size() > 1) return true;
  const auto held = holding_.find(client);
  return held == holding_.end() || held->second == 0;
}

std::optional<uint64_t> Scheduler::first_in_line() const {
  std::optional<uint64_t> first;
  double least = 0;
  for (const Waiter& w : waiting_) {
    if (!may_take(w.client)) continue;
    const double usage = device_->turns().usage(w.client);
    if (!first || usage < least) first = w.ticket, least = usage;  // earlier tickets win ties
  }
  return first;
}

bool Scheduler::may_overtake(uint64_t ticket, double estimated_ms) const {
  const std::optional<uint64_t> first = first_in_line();
  return first != ticket && estimated_ms <= options_.overtake_max_ms && short_of_memory_ &&
         short_of_memory_->first == first &&
         std::chrono::steady_clock::now() - short_of_memory_->second <
             std::chrono::milliseconds(options_.overtake_window_ms);
}

Scheduler::Lease Scheduler::acquire(const Ask& ask) {
  std::unique_lock<std::mutex> lock(mutex_);
  std::optional<Share> shared;
  // Those already waiting go first (but see may_overtake).
  if (idle_.empty() || !waiting_.empty() || !may_take(ask.client) ||
      !(shared = share(ask.device_bytes, ask.reply_bytes))) {
    // Waiters about to take a workspace just freed are not in the queue any more.
    const size_t queued = waiting_.size() - std::min(waiting_.size(), idle_.size());
    if (queued >= options_.max_queue)
      throw ResourceExhausted(
          "server queue", "the queue is full: " + std::to_string(options_.max_concurrent) +
                              " requests are rendering and " + std::to_string(queued) +
                              " are waiting (--max-queue " + std::to_string(options_.max_queue) +
                              "); retry later");
    const uint64_t ticket = next_ticket_++;
    waiting_.push_back({ticket, ask.client});
    const auto erase = [&] {
      waiting_.erase(std::find_if(waiting_.begin(), waiting_.end(),
                                  [&](const Waiter& w) { return w.ticket == ticket; }));
    };
    const auto leave = [&] {
      erase();
      freed_.notify_all();  // the next in line may be first now
    };
    bool emptied_idle = false;
    for (;;) {
      if (!idle_.empty() && first_in_line() == ticket) {
        if ((shared = share(ask.device_bytes, ask.reply_bytes))) break;
        if (!short_of_memory_ || short_of_memory_->first != ticket) {
          short_of_memory_.emplace(ticket, std::chrono::steady_clock::now());
          freed_.notify_all();  // small requests behind may go first now
        }
        // Nothing renders, so nothing that runs will give memory back: empty the idle
        // workspaces' scratch once; if that is not enough, the budget is held by replies,
        // uploads and requests waiting, and waiting here would hold up everyone behind.
        if (idle_.size() == options_.max_concurrent) {
          if (!emptied_idle) {
            std::vector<std::unique_ptr<Workspace>> emptied = empty_idle(nullptr);
            lock.unlock();
            emptied.clear();  // their buffers go back outside the lock
            lock.lock();
            emptied_idle = true;
            continue;
          }
          leave();
          throw ResourceExhausted(
              "memory_budget",
              "the request's " + std::to_string(ask.device_bytes) +
                  " bytes of device buffers and " + std::to_string(ask.reply_bytes) +
                  "-byte reply do not fit beside the " +
                  std::to_string(device_->allocated_bytes()) +
                  " bytes that replies being streamed, scene uploads, held scenes and waiting "
                  "requests hold of the server's " +
                  std::to_string(device_->budget_bytes()) +
                  "-byte memory budget (--memory-budget); retry later");
        }
      }
      if (!idle_.empty() && may_take(ask.client) && may_overtake(ticket, ask.estimated_ms) &&
          (shared = share(ask.device_bytes, ask.reply_bytes)))
        break;
      // Poll the caller's cancellation while waiting: a gRPC deadline has no callback here.
      // Memory that replies and uploads give back wakes no one either.
      freed_.wait_for(lock, std::chrono::milliseconds(20));
      if (ask.cancelled && ask.cancelled()) {
        leave();
        throw Cancelled();
      }
    }
    erase();
    if (idle_.size() > 1 && !waiting_.empty()) freed_.notify_all();
  }
  auto pick = std::find_if(idle_.rbegin(), idle_.rend(), [&](const auto& w) {
    return ask.sequence ? w->sequence() == ask.sequence : ask.scene && w->warm_scene() == ask.scene;
  });
  if (pick == idle_.rend())
    pick = std::find_if(idle_.rbegin(), idle_.rend(), [](const auto& w) {
      return w->warm_scene() == nullptr && w->sequence() == 0;
    });
  if (pick == idle_.rend()) pick = std::prev(idle_.rend());  // released first
  std::unique_ptr<Workspace> ws = std::move(*pick);
  idle_.erase(std::next(pick).base());
  // Another sequence's, between its frames: its state goes.
  if (ws->sequence() != 0 && ws->sequence() != ask.sequence) ws->end_sequence();
  trim_at_.reset();  // busy again
  ++holding_[ask.client];
  ws->pledge(std::move(shared->pledge));
  if (ask.reply) *ask.reply = std::move(shared->reply);
  return Lease(*this, std::move(ws), ask.client);
}

void Scheduler::release(std::unique_ptr<Workspace> ws, const std::string& client) {
  ws->pledge({});                                   // what its request did not draw goes back
  std::vector<std::unique_ptr<Workspace>> emptied;  // released outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (auto held = holding_.find(client); held != holding_.end() && --held->second == 0)
      holding_.erase(held);
    const Workspace* last = ws.get();
    idle_.push_back(std::move(ws));
    // Workspaces keep the buffers they grew while requests keep coming (fresh buffers cost page
    // faults, ~1 ms per 4 MB); an idle engine gives them back (SchedulerOptions::
    // idle_memory_bytes). The one just released stays if it keeps results for its held scene
    // (Workspace::warm_scene): a client's next request on that scene continues from them.
    if (options_.idle_trim_delay_ms == 0) {
      emptied = trim(last);
    } else if (idle_.size() == options_.max_concurrent && waiting_.empty()) {
      trim_at_ =
          std::chrono::steady_clock::now() + std::chrono::milliseconds(options_.idle_trim_delay_ms);
      trim_spare_ = last;
      trim_wake_.notify_one();
    }
  }
  freed_.notify_all();
}

}  // namespace shadow
