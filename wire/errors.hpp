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
  FieldError(std::string field, std::string why)
      : std::runtime_error(field + ": " + why), field_(std::move(field)), why_(std::move(why)) {}
  const std::string& field() const { return field_; }
  const std::string& why() const { return why_; }

 private:
  std::string field_;
  std::string why_;
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

// A request names something the server does not hold (an unknown or evicted scene id); maps
// to NOT_FOUND.
class NotFound : public FieldError {
 public:
  using FieldError::FieldError;
};

// Runs `check`, and rethrows a field error it raises with the field renamed by `rename` (the
// same error inside a bigger message, e.g. a sequence's frame).
template <class Check, class Rename>
void with_field_renamed(Check check, Rename rename) {
  try {
    check();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(rename(e.field()), e.why());
  } catch (const ResourceExhausted& e) {
    throw ResourceExhausted(rename(e.field()), e.why());
  } catch (const NotFound& e) {
    throw NotFound(rename(e.field()), e.why());
  }
}

// The request's client cancelled it or its deadline passed: the engine stops at the next launch
// or read (cl::Runtime::set_cancelled); maps to CANCELLED or DEADLINE_EXCEEDED.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("the request was cancelled or its deadline passed") {}
};

}  // namespace shadow
