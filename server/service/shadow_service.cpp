#include "service/shadow_service.hpp"

#include <chrono>

#include "engine/errors.hpp"
#include "service/convert.hpp"
#include "service/status.hpp"

namespace shadow::service {

grpc::Status ShadowServiceImpl::Render(grpc::ServerContext* context,
                                       const v1::RenderRequest* request,
                                       grpc::ServerWriter<v1::RenderResponse>* writer) {
  try {
    const RenderRequest engine_request = convert::from_proto(*request);
    // IsCancelled() covers both the client's cancel and its deadline; the engine asks it while
    // the request waits for a workspace and before every launch.
    const RenderResult result =
        engine_.render(engine_request, [context] { return context->IsCancelled(); });
    // Streaming holds no workspace: a slow reader does not hold up other requests.
    const bool sent = convert::stream_result(
        result, chunk_bytes_, [&](const v1::RenderResponse& r) { return writer->Write(r); });
    if (!sent) return {grpc::StatusCode::CANCELLED, "the client went away during streaming"};
    return grpc::Status::OK;
  } catch (const Cancelled&) {
    if (std::chrono::system_clock::now() >= context->deadline())
      return {grpc::StatusCode::DEADLINE_EXCEEDED, "the deadline passed; the render was stopped"};
    return {grpc::StatusCode::CANCELLED, "cancelled by the client; the render was stopped"};
  } catch (...) {
    return status_from_current_exception();
  }
}

}  // namespace shadow::service
