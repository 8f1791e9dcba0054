// ShadowService over shadow::Engine: proto -> engine request, the engine's render (it runs a
// few at once and queues the rest), and the result streamed back as a header plus bounded chunks.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <limits>

#include "engine/engine.hpp"
#include "service/request_log.hpp"
#include "service/scene_cache.hpp"
#include "service/security.hpp"
#include "service/stall_watchdog.hpp"
#include "service/statistics.hpp"
#include "shadow/v1/shadow.grpc.pb.h"
#include "wire/convert.hpp"
#include "wire/result_slicer.hpp"

namespace shadow::service {

class ShadowServiceImpl final : public v1::ShadowService::Service {
 public:
  // A reader that takes no message, or an upload that sends none, for `stall_timeout` is
  // cancelled. Each tenant may have `tenant_max_concurrent` requests rendering, waiting or
  // uploading (0: no limit).
  // Each call ends with a line in the request log (`log`).
  // Uploaded scenes are kept under `scene_cache` budgets.
  ShadowServiceImpl(Engine& engine, size_t chunk_bytes, std::chrono::milliseconds stall_timeout,
                    unsigned tenant_max_concurrent = 0, LogFormat log = LogFormat::kNone,
                    SceneCache::Limits scene_cache = {})
      : engine_(engine),
        chunk_bytes_(chunk_bytes),
        watchdog_(stall_timeout),
        tenants_(tenant_max_concurrent),
        log_(log),
        scenes_(scene_cache, [&engine](uint64_t bytes) {
          return engine.reserve(bytes, "uploaded scene kept (--scene-cache-bytes)");
        }) {}

  grpc::Status Render(grpc::ServerContext* context, const v1::RenderRequest* request,
                      grpc::ServerWriter<v1::RenderResponse>* writer) override;
  grpc::Status UploadScene(grpc::ServerContext* context,
                           grpc::ServerReader<v1::SceneUpload>* reader,
                           v1::SceneRef* reply) override;
  grpc::Status RenderSequence(grpc::ServerContext* context, const v1::SequenceRequest* request,
                              grpc::ServerWriter<v1::RenderResponse>* writer) override;
  grpc::Status GetStatistics(grpc::ServerContext* context, const v1::StatisticsRequest* request,
                             v1::Statistics* reply) override;
  grpc::Status Estimate(grpc::ServerContext* context, const v1::EstimateRequest* request,
                        v1::Price* reply) override;

  // The drain (ShadowServer::shutdown): from now on every new call is refused UNAVAILABLE ("the
  // server is shutting down"), so clients retry on another replica; from `stop_by` on, work
  // still running stops at its next launch and its call ends UNAVAILABLE too.
  void drain(std::chrono::steady_clock::time_point stop_by) {
    stop_by_.store(stop_by.time_since_epoch().count());
    draining_ = true;
  }
  // Calls being handled now (renders, sequences, uploads, statistics, estimates).
  int calls_in_flight() const { return in_flight_.load(); }

 private:
  Engine& engine_;
  size_t chunk_bytes_;
  StallWatchdog watchdog_;
  TenantLimiter tenants_;
  Statistics statistics_;
  RequestLog log_;
  SceneCache scenes_;
  // steady_clock ticks of stop_by's time; max: not stopping.
  std::atomic<int64_t> stop_by_{std::numeric_limits<int64_t>::max()};
  std::atomic<bool> draining_{false};
  mutable std::atomic<int> in_flight_{0};
  // Counts a call in flight while it lives; refused() says whether the drain refuses it.
  struct InFlight {
    explicit InFlight(const ShadowServiceImpl& s) : service(s) { ++s.in_flight_; }
    ~InFlight() { --service.in_flight_; }
    const ShadowServiceImpl& service;
  };
  static grpc::Status draining_status() {
    return {grpc::StatusCode::UNAVAILABLE,
            "the server is shutting down (SIGTERM); retry on another replica"};
  }
  bool stopping() const {
    return std::chrono::steady_clock::now().time_since_epoch().count() >= stop_by_.load();
  }
  // The engine's cancel check for a call: the client's cancel or deadline, or the drain's end.
  std::function<bool()> cancel_check(grpc::ServerContext* context) const {
    return [this, context] { return context->IsCancelled() || stopping(); };
  }
  // The status of a call the engine stopped (as the current exception): UNAVAILABLE when the
  // drain stopped it (`frames_sent` of a sequence named), else by its cause.
  grpc::Status stopped_status(const grpc::ServerContext& context, int64_t frames_sent = -1) const;

  // Each call's work; they fill what the statistics and the log need of them.
  grpc::Status render(grpc::ServerContext* context, const v1::RenderRequest& request,
                      grpc::ServerWriter<v1::RenderResponse>* writer, CallRecord& call,
                      LogLine& line);
  grpc::Status render_sequence(grpc::ServerContext* context, const v1::SequenceRequest& request,
                               grpc::ServerWriter<v1::RenderResponse>* writer, CallRecord& call,
                               LogLine& line);
  grpc::Status upload(grpc::ServerContext* context, grpc::ServerReader<v1::SceneUpload>* reader,
                      v1::SceneRef& reply, const std::string& tenant, LogLine& line);
  // Runs `work`, then records the call in the statistics and the log.
  template <class Work>
  grpc::Status served(grpc::ServerContext* context, LogLine line, Work work);
  // The scene a request names by id, for the call's tenant.
  convert::SceneLookup scene_lookup(const std::string& tenant);
  // Streams one result (a header and its chunks); CANCELLED when the client stops reading.
  grpc::Status send(grpc::ServerContext* context, const RenderResult& result,
                    ChunkCompression compression, grpc::ServerWriter<v1::RenderResponse>* writer);
  // Progress messages for a call that asked for them (`asked`; else nothing): while the work is
  // predicted over kProgressAfterMs of device time, or once it has run that long, one every
  // kProgressEveryMs at most, written from the rendering thread. A write that stalls is cancelled
  // by the watchdog, as a chunk's is.
  Engine::Progress progress_writer(grpc::ServerContext* context,
                                   grpc::ServerWriter<v1::RenderResponse>* writer, bool asked);
  static constexpr double kProgressAfterMs = 500, kProgressEveryMs = 250;
};

}  // namespace shadow::service
