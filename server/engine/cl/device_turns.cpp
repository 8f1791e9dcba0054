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

void DeviceTurns::take(const std::string& client) {
  std::unique_lock<std::mutex> lock(mutex_);
  ++account(client).waiting;
  const uint64_t ticket = next_ticket_++;
  waiting_.push_back({ticket, client});
  changed_.wait(lock, [&] { return !busy_ && next(ticket, client); });
  busy_ = true;
  waiting_.remove_if([&](const Waiter& w) { return w.ticket == ticket; });
  --accounts_.at(client).waiting;
}

void DeviceTurns::give(const std::string& client, double ms) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    Account& a = account(client);
    a.usage += ms / weight(client);
    a.total_ms += ms;
    busy_ = false;
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
