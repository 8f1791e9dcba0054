#include "service/shadow_service.hpp"

#include <charconv>
#include <chrono>

#include "service/status.hpp"
#include "wire/convert.hpp"
#include "wire/errors.hpp"
#include "wire/names.hpp"

namespace shadow::service {
namespace {

// gRPC's retry policy numbers its attempts in this header (gRFC A6); absent on a first attempt.
unsigned previous_attempts(const grpc::ServerContext& context) {
  const auto& metadata = context.client_metadata();
  const auto found = metadata.find("grpc-previous-rpc-attempts");
  if (found == metadata.end()) return 0;
  unsigned n = 0;
  const grpc::string_ref value = found->second;
  const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), n);
  return error == std::errc() && end == value.data() + value.size() ? n : 0;
}

}  // namespace

grpc::Status ShadowServiceImpl::Render(grpc::ServerContext* context,
                                       const v1::RenderRequest* request,
                                       grpc::ServerWriter<v1::RenderResponse>* writer) {
  const auto start = std::chrono::steady_clock::now();
  CallRecord call;
  call.tenant = tenant_of(*context);
  LogLine line;
  line.request_bytes = request->ByteSizeLong();
  for (int i = 0; i < request->products_size(); ++i) {
    const auto product = names::kProducts.from_proto(request->products(i));
    line.products.emplace_back(product ? names::kProducts.name(*product) : "?");
  }
  const grpc::Status status = render(context, *request, writer, call, line.reply_bytes);
  call.code = status.error_code();
  statistics_.record(call);
  line.tenant = call.tenant;
  line.peer = context->peer();
  line.previous_attempts = previous_attempts(*context);
  line.code = call.code;
  line.message = status.error_message();
  line.queue_ms = call.queue_ms, line.run_ms = call.run_ms;
  line.total_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  log_.write(line);
  return status;
}

grpc::Status ShadowServiceImpl::GetStatistics(grpc::ServerContext* context,
                                              const v1::StatisticsRequest*, v1::Statistics* reply) {
  // With tokens a tenant sees its own work only.
  const std::string tenant = tenant_of(*context);
  *reply = statistics_.snapshot(tenant.empty() ? nullptr : &tenant);
  const Engine::Load load = engine_.load();
  reply->set_workspaces_busy(load.rendering);
  reply->set_workspaces(load.workspaces);
  reply->set_requests_waiting(load.waiting);
  reply->set_device_memory_bytes(engine_.device_bytes_in_use());
  reply->set_device_memory_budget(engine_.memory_budget_bytes());
  return grpc::Status::OK;
}

grpc::Status ShadowServiceImpl::render(grpc::ServerContext* context, const v1::RenderRequest& proto,
                                       grpc::ServerWriter<v1::RenderResponse>* writer,
                                       CallRecord& call, uint64_t& reply_bytes) {
  const v1::RenderRequest* request = &proto;
  try {
    const TenantLimiter::Slot slot = tenants_.acquire(call.tenant);
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
    call.rendered = true;
    call.queue_ms = result.queue_ms, call.run_ms = result.run_ms;
    call.timings = result.timings;
    for (const Texture& t : result.textures) reply_bytes += t.byte_size();
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
