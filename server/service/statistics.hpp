// What the server has done, per tenant and in total (GetStatistics, in the spirit of Triton's
// statistics extension): calls by status code, queue and run time percentiles over a window of
// recent renders, and device time per pass. Thread-safe.
#pragma once

#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <grpcpp/support/status.h>

#include "shadow/v1/shadow.pb.h"
#include "wire/types.hpp"

namespace shadow::service {

// One Render call as it ended.
struct CallRecord {
  std::string tenant;
  grpc::StatusCode code = grpc::StatusCode::OK;
  bool rendered = false;  // the engine finished: the times and timings below are set
  double queue_ms = 0, run_ms = 0;
  std::vector<PassTiming> timings;
};

class Statistics {
 public:
  static constexpr size_t kWindow = 4096;  // renders per tenant the percentiles look at

  void record(const CallRecord& call);

  // Every tenant and the total; or, for `only_tenant`, that tenant alone (also as the total).
  v1::Statistics snapshot(const std::string* only_tenant = nullptr) const;

 private:
  struct Tenant {
    std::map<grpc::StatusCode, uint64_t> calls;
    std::deque<double> queue_ms, run_ms;                        // the last kWindow renders
    std::map<std::string, std::pair<uint64_t, double>> passes;  // runs, device ms
    void add(const CallRecord& call);
    v1::TenantStatistics to_proto(const std::string& name) const;
  };

  mutable std::mutex mutex_;
  Tenant total_;
  std::map<std::string, Tenant> tenants_;
};

}  // namespace shadow::service
