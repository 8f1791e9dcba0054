// Errors raised by the engine and by the wire conversion (a bad field on the wire is an
// InvalidArgument like a bad value). The service maps them to gRPC status codes in one place.
#pragma once

#include <stdexcept>
#include <string>

namespace shadow {

// An error about one request field. `field` is its proto path, e.g.
// "scene.meshes[3].indices[17]"; the message starts with it.
class FieldError : public std::runtime_error {
 public:
  FieldError(std::string field, const std::string& why)
      : std::runtime_error(field + ": " + why), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

// Bad client input; maps to INVALID_ARGUMENT.
class InvalidArgument : public FieldError {
 public:
  using FieldError::FieldError;
};

// A request over a server limit (output bytes, device memory), naming the field that drove
// the size; maps to RESOURCE_EXHAUSTED.
class ResourceExhausted : public FieldError {
 public:
  using FieldError::FieldError;
};

// The request's client cancelled it or its deadline passed: the engine stops at the next launch
// or read (cl::Runtime::set_cancelled); maps to CANCELLED or DEADLINE_EXCEEDED.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("the request was cancelled or its deadline passed") {}
};

}  // namespace shadow
