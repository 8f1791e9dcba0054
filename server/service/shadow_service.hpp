// ShadowService over shadow::Engine: proto -> engine request, the engine's render (it runs a
// few at once and queues the rest), and the result streamed back as a header plus bounded chunks.
#pragma once

#include "engine/engine.hpp"
#include "service/texture_stream.hpp"
#include "shadow/v1/shadow.grpc.pb.h"

namespace shadow::service {

class ShadowServiceImpl final : public v1::ShadowService::Service {
 public:
  explicit ShadowServiceImpl(Engine& engine, size_t chunk_bytes = convert::kDefaultChunkBytes)
      : engine_(engine), chunk_bytes_(chunk_bytes) {}

  grpc::Status Render(grpc::ServerContext* context, const v1::RenderRequest* request,
                      grpc::ServerWriter<v1::RenderResponse>* writer) override;

 private:
  Engine& engine_;
  size_t chunk_bytes_;
};

}  // namespace shadow::service
