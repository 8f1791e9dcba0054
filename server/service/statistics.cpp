#include "service/statistics.hpp"

#include <algorithm>
#include <cmath>

#include "wire/status_names.hpp"

namespace shadow::service {
namespace {

void push(std::deque<double>& window, double value) {
  window.push_back(value);
  if (window.size() > Statistics::kWindow) window.pop_front();
}

// Nearest-rank percentiles.
v1::Percentiles percentiles(const std::deque<double>& window) {
  v1::Percentiles out;
  std::vector<double> v(window.begin(), window.end());
  out.set_samples(v.size());
  if (v.empty()) return out;
  std::sort(v.begin(), v.end());
  auto at = [&](double p) { return v[size_t(std::ceil(p * double(v.size()))) - 1]; };
  out.set_p50_ms(at(0.50));
  out.set_p90_ms(at(0.90));
  out.set_p99_ms(at(0.99));
  out.set_max_ms(v.back());
  return out;
}

}  // namespace

void Statistics::Tenant::add(const CallRecord& call) {
  ++calls[call.code];
  if (!call.rendered) return;
  push(queue_ms, call.queue_ms);
  push(run_ms, call.run_ms);
  for (const PassTiming& t : call.timings) {
    auto& [runs, ms] = passes[t.pass];
    ++runs;
    ms += t.device_ms;
  }
}

v1::TenantStatistics Statistics::Tenant::to_proto(const std::string& name) const {
  v1::TenantStatistics out;
  out.set_tenant(name);
  std::map<std::string, uint64_t> by_name;  // name order, as documented
  for (const auto& [code, n] : calls) by_name[status_code_name(code)] = n;
  for (const auto& [code, n] : by_name) {
    v1::StatusCount* c = out.add_requests();
    c->set_code(code);
    c->set_count(n);
  }
  *out.mutable_queue_time() = percentiles(queue_ms);
  *out.mutable_run_time() = percentiles(run_ms);
  for (const auto& [pass, runs_ms] : passes) {
    v1::PassStatistics* p = out.add_passes();
    p->set_pass(pass);
    p->set_runs(runs_ms.first);
    p->set_device_ms(runs_ms.second);
  }
  return out;
}

void Statistics::record(const CallRecord& call) {
  std::lock_guard<std::mutex> lock(mutex_);
  total_.add(call);
  tenants_[call.tenant].add(call);
}

v1::Statistics Statistics::snapshot(const std::string* only_tenant) const {
  std::lock_guard<std::mutex> lock(mutex_);
  v1::Statistics out;
  if (only_tenant) {
    const auto t = tenants_.find(*only_tenant);
    const Tenant& mine = t == tenants_.end() ? Tenant{} : t->second;
    *out.mutable_total() = mine.to_proto(*only_tenant);
    *out.add_tenants() = mine.to_proto(*only_tenant);
    return out;
  }
  *out.mutable_total() = total_.to_proto("");
  for (const auto& [name, tenant] : tenants_) *out.add_tenants() = tenant.to_proto(name);
  return out;
}

}  // namespace shadow::service
