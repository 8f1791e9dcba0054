// ShadowService over shadow::Engine: proto -> engine request, the engine's render (it runs a
// few at once and queues the rest), and the result streamed back as a header plus bounded chunks.
#pragma once

#include <chrono>

#include "engine/engine.hpp"
#include "service/stall_watchdog.hpp"
#include "shadow/v1/shadow.grpc.pb.h"
#include "wire/result_slicer.hpp"

namespace shadow::service {

class ShadowServiceImpl final : public v1::ShadowService::Service {
 public:
  // A reader that takes no message for `stall_timeout` is cancelled.
  ShadowServiceImpl(Engine& engine, size_t chunk_bytes, std::chrono::milliseconds stall_timeout)
      : engine_(engine), chunk_bytes_(chunk_bytes), watchdog_(stall_timeout) {}

  grpc::Status Render(grpc::ServerContext* context, const v1::RenderRequest* request,
                      grpc::ServerWriter<v1::RenderResponse>* writer) override;

 private:
  Engine& engine_;
  size_t chunk_bytes_;
  StallWatchdog watchdog_;
};

}  // namespace shadow::service
