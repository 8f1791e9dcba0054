// A plaintext server that answers grpc.health.v1 and nothing else (shadow-server
// --health-listen), for probes that cannot speak TLS: Kubernetes' built-in gRPC probe.
#pragma once

#include <memory>
#include <string>

#include <grpcpp/server.h>

namespace shadow::service {

// Listens on `listen` ("HOST:PORT", port 0 picks one; the address bound goes to `address`);
// SERVING from the start, the caller mirrors the main server's status on it. Throws naming
// --health-listen when it cannot listen.
std::unique_ptr<grpc::Server> start_health_server(const std::string& listen, std::string* address);

}  // namespace shadow::service
