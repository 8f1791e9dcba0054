// gRPC status codes by name ("INVALID_ARGUMENT"), for the server's statistics and request log
// and for shadowctl's messages.
#pragma once

#include <string>

#include <grpcpp/support/status.h>

namespace shadow {

// The code's name as in grpc/status.h, or "status N" for a number gRPC does not define.
std::string status_code_name(grpc::StatusCode code);

}  // namespace shadow
