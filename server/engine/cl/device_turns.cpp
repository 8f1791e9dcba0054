#include "engine/cl/device_turns.hpp"

#include <algorithm>
#include <limits>

namespace shadow::cl {

void DeviceTurns::set_weights(std::map<std::string, double> weights) {
  std::lock_guard<std::mutex> lock(mutex_);
  weights_ = std::move(weights);
}

double DeviceTurns::weight(const std::string& client) const {
  const auto found = weights_.find(client);
  return found == weights_.end() ? 1.0 : found->second;
}

double DeviceTurns::floor() const {
  double least = std::numeric_limits<double>::infinity();
  for (const auto& [name, a] : accounts_)
    if (a.active > 0 || a.waiting > 0) least = std::min(least, a.usage);
  if (least != std::numeric_limits<double>::infinity()) last_floor_ = std::max(last_floor_, least);
  return last_floor_;
}

DeviceTurns::Account& DeviceTurns::account(const std::string& client) {
  auto found = accounts_.find(client);
  if (found == accounts_.end()) {
    prune();
    found = accounts_.emplace(client, Account{}).first;
    found->second.usage = floor();
  } else if (found->second.active == 0 && found->second.waiting == 0) {
    const double least = floor();
    found->second.usage = std::clamp(found->second.usage, least, least + kMemoryMs);
  }
  return found->second;
}

void DeviceTurns::prune() {
  if (accounts_.size() < kMaxAccounts) return;
  // The idle client charged least goes: its total is the smallest loss to the statistics.
  auto victim = accounts_.end();
  for (auto it = accounts_.begin(); it != accounts_.end(); ++it)
    if (it->second.active == 0 && it->second.waiting == 0 &&
        (victim == accounts_.end() || it->second.total_ms < victim->second.total_ms))
      victim = it;
  if (victim != accounts_.end()) accounts_.erase(victim);
}

bool DeviceTurns::next(uint64_t ticket, const std::string& client) {
  const Waiter* best = nullptr;
  double best_usage = 0;
  for (const Waiter& w : waiting_) {
    const double u = accounts_.at(w.client).usage;
    if (!best || u < best_usage || (u == best_usage && w.ticket < best->ticket))
      best = &w, best_usage = u;
  }
  return best && best->ticket == ticket && best->client == client;
}

void DeviceTurns::take(const std::string& client, const void* owner) {
  std::unique_lock<std::mutex> lock(mutex_);
  ++account(client).waiting;
  const uint64_t ticket = next_ticket_++;
  waiting_.push_back({ticket, client});
  for (;;) {
    if (running_ == 0 && (client == held_for_ || next(ticket, client))) {
      // Held for another client: wait for its next launch until the hold ends.
      if (held_for_.empty() || client == held_for_ ||
          std::chrono::steady_clock::now() >= held_until_)
        break;
      changed_.wait_until(lock, held_until_);
      continue;
    }
    changed_.wait(lock);
  }
  held_for_.clear();
  running_ = 1;
  holder_ = owner;
  waiting_.remove_if([&](const Waiter& w) { return w.ticket == ticket; });
  --accounts_.at(client).waiting;
}

bool DeviceTurns::take_behind(const std::string& client, const void* owner) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (running_ != 1 || holder_ != owner) return false;
  const double own = account(client).usage;
  for (const Waiter& w : waiting_)
    if (accounts_.at(w.client).usage < own) return false;
  running_ = 2;
  return true;
}

void DeviceTurns::give(const std::string& client, double ms) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    Account& a = account(client);
    a.usage += ms / weight(client);
    a.total_ms += ms;
    if (--running_ > 0) return;  // its second command runs on
    // Ahead of every waiting client: the device waits a moment for its next launch.
    const bool ahead = std::all_of(waiting_.begin(), waiting_.end(), [&](const Waiter& w) {
      return a.usage <= accounts_.at(w.client).usage;
    });
    held_for_ = ahead ? client : std::string();
    held_until_ = std::chrono::steady_clock::now() + kHold;
  }
  changed_.notify_all();
}

double DeviceTurns::usage(const std::string& client) {
  std::lock_guard<std::mutex> lock(mutex_);
  return account(client).usage;
}

void DeviceTurns::enter(const std::string& client) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++account(client).active;
}

void DeviceTurns::leave(const std::string& client) {
  std::lock_guard<std::mutex> lock(mutex_);
  Account& a = account(client);
  if (a.active > 0) --a.active;
}

std::vector<DeviceTurns::Total> DeviceTurns::totals() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Total> out;
  for (const auto& [name, a] : accounts_)
    if (a.total_ms > 0) out.push_back({name, a.total_ms});
  std::sort(out.begin(), out.end(), [](const Total& a, const Total& b) { return a.ms > b.ms; });
  return out;
}

}  // namespace shadow::cl
