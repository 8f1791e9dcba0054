// ShadowService over shadow::Engine: proto -> engine request, the engine's render (it runs a
// few at once and queues the rest), and the result streamed back as a header plus bounded chunks.
#pragma once

#include <chrono>

#include "engine/engine.hpp"
#include "service/request_log.hpp"
#include "service/security.hpp"
#include "service/stall_watchdog.hpp"
#include "service/statistics.hpp"
#include "shadow/v1/shadow.grpc.pb.h"
#include "wire/result_slicer.hpp"

namespace shadow::service {

class ShadowServiceImpl final : public v1::ShadowService::Service {
 public:
  // A reader that takes no message for `stall_timeout` is cancelled.
  // Each tenant may have `tenant_max_concurrent` requests rendering or waiting (0: no limit).
  // Each call ends with a line in the request log (`log`).
  ShadowServiceImpl(Engine& engine, size_t chunk_bytes, std::chrono::milliseconds stall_timeout,
                    unsigned tenant_max_concurrent = 0, LogFormat log = LogFormat::kNone)
      : engine_(engine),
        chunk_bytes_(chunk_bytes),
        watchdog_(stall_timeout),
        tenants_(tenant_max_concurrent),
        log_(log) {}

  grpc::Status Render(grpc::ServerContext* context, const v1::RenderRequest* request,
                      grpc::ServerWriter<v1::RenderResponse>* writer) override;
  grpc::Status GetStatistics(grpc::ServerContext* context, const v1::StatisticsRequest* request,
                             v1::Statistics* reply) override;

 private:
  Engine& engine_;
  size_t chunk_bytes_;
  StallWatchdog watchdog_;
  TenantLimiter tenants_;
  Statistics statistics_;
  RequestLog log_;

  // Render's work; fills what the statistics need of it.
  grpc::Status render(grpc::ServerContext* context, const v1::RenderRequest& request,
                      grpc::ServerWriter<v1::RenderResponse>* writer, CallRecord& call,
                      uint64_t& reply_bytes);
};

}  // namespace shadow::service
