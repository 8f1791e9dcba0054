#include "service/shadow_service.hpp"

#include <chrono>

#include "service/status.hpp"
#include "wire/convert.hpp"
#include "wire/errors.hpp"

namespace shadow::service {

grpc::Status ShadowServiceImpl::Render(grpc::ServerContext* context,
                                       const v1::RenderRequest* request,
                                       grpc::ServerWriter<v1::RenderResponse>* writer) {
  try {
    const TenantLimiter::Slot slot = tenants_.acquire(tenant_of(*context));
    // The request's message and its engine copy count against the memory budget while it
    // waits and renders; the reply's textures while they are streamed.
    const cl::Reservation request_memory =
        engine_.reserve(2 * uint64_t{request->ByteSizeLong()}, "request");
    const RenderRequest engine_request = convert::from_proto(*request);
    const ChunkCompression compression =
        convert::from_proto(request->chunk_compression(), "chunk_compression");
    cl::Reservation reply_memory;
    // IsCancelled() covers both the client's cancel and its deadline; the engine asks it while
    // the request waits for a workspace and before every launch.
    const RenderResult result = engine_.render(
        engine_request, [context] { return context->IsCancelled(); }, &reply_memory);
    // Streaming holds no workspace: a slow reader does not hold up other requests, and one that
    // stops reading is cancelled by the watchdog.
    StallWatchdog::Watch watch(watchdog_, context);
    const bool sent = convert::stream_result(
        result, chunk_bytes_,
        [&](const v1::RenderResponse& r) {
          const bool ok = writer->Write(r);
          if (ok) watch.progress();
          return ok;
        },
        compression);
    if (!sent && watch.stalled())
      return {grpc::StatusCode::CANCELLED, "the client read nothing for the stall timeout"};
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
