// A running shadow server: the engine, the ShadowService, health checking and reflection on
// one gRPC server. Used by shadow-server's main and by the tests, so both serve the same way.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/server.h>

#include "engine/engine.hpp"
#include "service/security.hpp"
#include "service/shadow_service.hpp"

namespace shadow::service {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";  // port 0 picks a free port
  EngineOptions engine;
  int max_request_bytes = 512 << 20;  // a scene travels inline in one message
  size_t chunk_bytes = convert::kDefaultChunkBytes;
  // A reader that takes no reply message for this long is cancelled, freeing its reply.
  std::chrono::milliseconds stall_timeout = std::chrono::seconds(30);
  SecurityOptions security;                 // TLS, mTLS and tokens; plaintext when empty
  unsigned tenant_max_concurrent = 0;       // requests per tenant rendering or waiting; 0: no limit
  SceneCache::Limits scene_cache;           // uploaded scenes (UploadScene)
  LogFormat log_format = LogFormat::kNone;  // one line per Render call on stderr
  // Connections older than this are closed (GOAWAY; calls in flight may finish within the
  // grace), so clients balancing over a DNS name re-resolve and reach new replicas. 0: never.
  std::chrono::milliseconds max_connection_age{0};
  std::chrono::milliseconds max_connection_age_grace{0};  // 0: calls in flight run to their end
};

// Sets glibc's allocation thresholds for serving: RSS bounded, reply buffers reused. Call once,
// first, in a process that hosts a ShadowServer (shadow-server's main, the benchmarks).
void tune_allocator();

class ShadowServer {
 public:
  // Builds the engine (compiling every kernel), then starts serving. Throws if either fails.
  explicit ShadowServer(ServerOptions options);
  ~ShadowServer();  // shuts down if still running

  // The address actually bound, with the chosen port, e.g. "127.0.0.1:41234".
  const std::string& address() const { return address_; }
  int port() const { return port_; }
  Engine& engine() { return *engine_; }

  // Drains: health turns NOT_SERVING and new calls get UNAVAILABLE; calls in flight may finish
  // within `grace`, and what still renders just before it ends stops with UNAVAILABLE (a
  // sequence's status names the frames sent). Returns when no call is left. Idempotent.
  void shutdown(std::chrono::milliseconds grace = kShutdownGrace);
  // Below Kubernetes' 30 s terminationGracePeriodSeconds, so the drain ends before SIGKILL.
  static constexpr std::chrono::milliseconds kShutdownGrace{25000};

 private:
  ServerOptions options_;
  std::unique_ptr<Engine> engine_;
  std::unique_ptr<ShadowServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
  int port_ = 0;
  bool stopped_ = false;
};

// "cannot listen on ADDR (Address already in use: is another server using that port?)": the
// OS's reason from gRPC's log lines of the failed start (GrpcLogCapture), where they give one.
std::string cannot_listen(const std::string& listen, const std::vector<std::string>& grpc_log);

// The health-check service name that clients ask about.
inline constexpr const char* kServiceName = "shadow.v1.ShadowService";

}  // namespace shadow::service
