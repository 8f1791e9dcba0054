#include "service/server.hpp"

#include <malloc.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <stdexcept>
#include <thread>
#include <vector>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/resource_quota.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_builder.h>

#include "service/start_up.hpp"

namespace shadow::service {
namespace {

// The transport's quota for requests in transit: this share of the memory budget (at least one
// largest request).
constexpr uint64_t kTransportShare = 4;

// "host:port" with the port replaced; works for "[::1]:0" too.
std::string with_port(const std::string& listen, int port) {
  const auto colon = listen.rfind(':');
  return (colon == std::string::npos ? listen : listen.substr(0, colon)) + ":" +
         std::to_string(port);
}

}  // namespace

void tune_allocator() {
  // Device buffers (PoCL's are host memory) and replies are megabytes each. Left to itself,
  // glibc raises its mmap threshold to 32 MiB after the first large free and its heap keeps what
  // requests free: 4 heavy requests one after another under a 3.6 GB budget peaked at 6.3 GB of
  // RSS, and at 2.2 GB with the threshold fixed at 1 MiB (docs/benchmarks.md, "Hostile load").
  // Just above 1 MiB (room for a slice's header), with 32 MiB of free heap top kept, gRPC's
  // 1 MiB serialization slices are reused instead of mapped, faulted and unmapped two per chunk
  // sent: a 4096² map reaches shadowctl's disk 9% sooner, and the heavy requests' RSS peaks at
  // 2 274 MiB against 2 154-2 231 at 1 MiB (at 4 MiB, as fast: 2 764-2 801; "What a user waits
  // for").
  mallopt(M_MMAP_THRESHOLD, (1 << 20) + (64 << 10));
  mallopt(M_TRIM_THRESHOLD, 32 << 20);
}

std::string cannot_listen(const std::string& listen, const std::vector<std::string>& grpc_log) {
  std::string why;
  for (const std::string& line : grpc_log)
    if (why.empty()) why = os_error_in(line);
  if (why.empty() || why.find("in use") != std::string::npos)
    why += std::string(why.empty() ? "" : ": ") + "is another server using that port?";
  return "cannot listen on " + listen + " (" + why + ")";
}

ShadowServer::ShadowServer(ServerOptions options) : options_(std::move(options)) {
  // Before the engine: a bad certificate or token file fails the start at once.
  const std::shared_ptr<grpc::ServerCredentials> credentials =
      make_server_credentials(options_.security);
  engine_ = std::make_unique<Engine>(options_.engine);
  service_ = std::make_unique<ShadowServiceImpl>(
      *engine_, options_.chunk_bytes, options_.stall_timeout, options_.tenant_max_concurrent,
      options_.log_format, options_.scene_cache);

  // Both are process-wide switches that must be set before a server is built.
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();

  grpc::ServerBuilder builder;
  // gRPC sets SO_REUSEPORT by default, so a second server on a taken port would start and
  // silently split the traffic; without it, the bind fails and so does the start.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.AddListeningPort(options_.listen, credentials, &port_);
  builder.RegisterService(service_.get());
  builder.SetMaxReceiveMessageSize(options_.max_request_bytes);
  // gRPC receives a whole request message before the service can count it against the memory
  // budget. Its quota bounds what the transport holds meanwhile: near the quota it shrinks the
  // flow-control windows (senders wait) and past it cancels calls (RESOURCE_EXHAUSTED). 16
  // concurrent 200 MiB requests under a 2 GB budget peaked at 0.83x the budget with it, 1.30x
  // without (docs/benchmarks.md, "Hostile load").
  grpc::ResourceQuota quota("shadow-server");
  quota.Resize(size_t(std::max(engine_->memory_budget_bytes() / kTransportShare,
                               static_cast<uint64_t>(options_.max_request_bytes))));
  builder.SetResourceQuota(quota);
  // A connection may not have more calls open than can render or wait: gRPC receives a whole
  // request message before the service can count it against the memory budget, so further
  // calls on that connection wait at the client instead of in server memory.
  builder.AddChannelArgument(GRPC_ARG_MAX_CONCURRENT_STREAMS,
                             int(options_.engine.max_concurrent + options_.engine.max_queue));
  // Replies are a small header and chunks of chunk_bytes; leave room for framing.
  builder.SetMaxSendMessageSize(int(options_.chunk_bytes + (1 << 20)));
  if (options_.max_connection_age.count() > 0) {
    builder.AddChannelArgument(
        GRPC_ARG_MAX_CONNECTION_AGE_MS,
        int(std::min<int64_t>(options_.max_connection_age.count(), INT_MAX)));
    if (options_.max_connection_age_grace.count() > 0)
      builder.AddChannelArgument(
          GRPC_ARG_MAX_CONNECTION_AGE_GRACE_MS,
          int(std::min<int64_t>(options_.max_connection_age_grace.count(), INT_MAX)));
  }
  // gRPC logs a bind failure as a raw error line of its own; the server says it in one line.
  std::vector<std::string> bind_log;
  {
    GrpcLogCapture capture;
    server_ = builder.BuildAndStart();
    if (server_ && port_ != 0)
      capture.print();  // whatever gRPC said on a start that worked
    else
      bind_log = capture.lines();
  }
  if (!server_ || port_ == 0) throw std::runtime_error(cannot_listen(options_.listen, bind_log));
  address_ = with_port(options_.listen, port_);

  grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService();
  health->SetServingStatus(kServiceName, true);
  health->SetServingStatus("", true);
}

ShadowServer::~ShadowServer() {
  shutdown();
}

void ShadowServer::shutdown(std::chrono::milliseconds grace) {
  if (stopped_ || !server_) return;
  stopped_ = true;
  using Clock = std::chrono::steady_clock;
  const Clock::time_point end = Clock::now() + grace;
  // Health turns NOT_SERVING and new calls are refused UNAVAILABLE, so balancers and the
  // clients' retry go to another replica; work still running a fifth of the grace (at most 1 s)
  // before its end stops at its next launch slice with UNAVAILABLE, which the clients' resume
  // takes elsewhere (a sequence from its next frame), before gRPC would cancel its call with no
  // word at all.
  server_->GetHealthCheckService()->Shutdown();
  const std::chrono::milliseconds margin =
      std::min<std::chrono::milliseconds>(grace / 5, std::chrono::seconds(1));
  service_->drain(end - margin);
  while (service_->calls_in_flight() > 0 && Clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  // Nothing left, or the grace is over: what still streams is cancelled. A handler that returned
  // may still be sending its final status, which cancelling at once could lose: gRPC waits for
  // those up to the deadline, at most a second of what is left.
  const auto left = std::clamp<Clock::duration>(end - Clock::now(), Clock::duration::zero(),
                                                std::chrono::seconds(1));
  server_->Shutdown(std::chrono::system_clock::now() +
                    std::chrono::duration_cast<std::chrono::system_clock::duration>(left));
  server_->Wait();
}

}  // namespace shadow::service
