#include "service/shadow_service.hpp"

#include "service/convert.hpp"
#include "service/status.hpp"

namespace shadow::service {

grpc::Status ShadowServiceImpl::Render(grpc::ServerContext* context,
                                       const v1::RenderRequest* request,
                                       grpc::ServerWriter<v1::RenderResponse>* writer) {
  try {
    const RenderRequest engine_request = convert::from_proto(*request);
    RenderResult result;
    {
      std::lock_guard lock(engine_mutex_);
      // The client may have given up while it waited for its turn.
      if (context->IsCancelled()) return {grpc::StatusCode::CANCELLED, "cancelled by the client"};
      result = engine_.render(engine_request);
    }
    // Stream outside the lock: a slow reader must not hold up other requests.
    const bool sent = convert::stream_result(
        result, chunk_bytes_, [&](const v1::RenderResponse& r) { return writer->Write(r); });
    if (!sent) return {grpc::StatusCode::CANCELLED, "the client went away during streaming"};
    return grpc::Status::OK;
  } catch (...) {
    return status_from_current_exception();
  }
}

}  // namespace shadow::service
