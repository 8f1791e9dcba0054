// A typed C++ client over the generated ShadowService stub. It reassembles streamed texture
// chunks and converts the reply to the engine's vocabulary types (server/engine/types.hpp).
#pragma once

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include <grpcpp/grpcpp.h>

#include "engine/types.hpp"
#include "shadow/v1/shadow.grpc.pb.h"

namespace shadow::client {

// A failed RPC: the gRPC status code and the server's message (which names the bad field).
class RpcError : public std::runtime_error {
 public:
  RpcError(grpc::StatusCode code, const std::string& message)
      : std::runtime_error(message), code_(code) {}
  grpc::StatusCode code() const { return code_; }

 private:
  grpc::StatusCode code_;
};

class ShadowClient {
 public:
  explicit ShadowClient(const std::string& address);  // e.g. "127.0.0.1:50051", insecure
  explicit ShadowClient(std::shared_ptr<grpc::Channel> channel);

  // Sends the request and returns every product, reassembled. Throws RpcError.
  RenderResult render(const v1::RenderRequest& request,
                      std::chrono::milliseconds deadline = std::chrono::minutes(5));
  RenderResult render(const RenderRequest& request,
                      std::chrono::milliseconds deadline = std::chrono::minutes(5));

  // True when grpc.health.v1 reports SERVING for "shadow.v1.ShadowService".
  bool healthy(std::chrono::milliseconds deadline = std::chrono::seconds(2));

 private:
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::ShadowService::Stub> stub_;
};

}  // namespace shadow::client
