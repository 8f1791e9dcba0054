// Collects the profiling events of one request, grouped by pass name in the order each pass
// first ran, and the passes kept from an earlier frame or run again. While a light of several
// renders, every pass name gets its prefix ("light1.").
#pragma once

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "engine/cl/runtime.hpp"
#include "wire/types.hpp"

namespace shadow {

class Timeline {
 public:
  void set_prefix(std::string prefix) { prefix_ = std::move(prefix); }
  // The pass's name as recorded: with the current prefix.
  std::string scoped(const std::string& pass) const { return prefix_ + pass; }

  void add(const std::string& unscoped, cl::Event event) {
    const std::string pass = scoped(unscoped);
    if (std::find(passes_.begin(), passes_.end(), pass) == passes_.end()) passes_.push_back(pass);
    if (event) events_.emplace_back(pass, std::move(event));
  }
  void add(const std::string& pass, cl::Events events) {
    if (events.empty()) add(pass, cl::Event());
    for (cl::Event& e : events) add(pass, std::move(e));
  }
  const std::vector<std::string>& passes() const { return passes_; }

  // A pass that did not run because its earlier result still holds (passes/step_cache.hpp: a
  // hit), and one that ran again because an input changed (a miss).
  void reuse(const std::string& unscoped) { reused_.push_back(scoped(unscoped)); }
  void rerun(const std::string& unscoped) { rerun_.push_back(scoped(unscoped)); }
  const std::vector<std::string>& reused() const { return reused_; }
  const std::vector<std::string>& reran() const { return rerun_; }

  // Device time per pass (sums the pass's events); call once the queue has finished.
  std::vector<PassTiming> timings() const {
    std::vector<PassTiming> out;
    for (const std::string& p : passes_) {
      double ms = 0.0;
      for (const auto& [name, e] : events_)
        if (name == p) ms += cl::event_ms(e);
      out.push_back({p, ms});
    }
    return out;
  }

 private:
  std::string prefix_;
  std::vector<std::string> passes_;
  std::vector<std::string> reused_, rerun_;
  std::vector<std::pair<std::string, cl::Event>> events_;
};

}  // namespace shadow
