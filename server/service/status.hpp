// The one place where exceptions become gRPC statuses.
#pragma once

#include <grpcpp/support/status.h>

namespace shadow::service {

// Call only from inside a catch block. InvalidArgument -> INVALID_ARGUMENT and
// ResourceExhausted -> RESOURCE_EXHAUSTED, both with a message that starts with the field path;
// std::bad_alloc -> RESOURCE_EXHAUSTED; anything else -> INTERNAL (and logged).
grpc::Status status_from_current_exception();

}  // namespace shadow::service
