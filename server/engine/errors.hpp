// Errors raised inside the engine. The service maps them to gRPC status codes in one place.
#pragma once

#include <stdexcept>
#include <string>

namespace shadow {

// Bad client input. `field` is the proto path of the offending value, e.g.
// "scene.meshes[3].indices[17]"; maps to INVALID_ARGUMENT.
class InvalidArgument : public std::runtime_error {
 public:
  InvalidArgument(std::string field, const std::string& why)
      : std::runtime_error(field + ": " + why), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

// A request that would exceed a server limit (output bytes, device memory); maps to
// RESOURCE_EXHAUSTED and names the field that drove the size.
class ResourceExhausted : public std::runtime_error {
 public:
  ResourceExhausted(std::string field, const std::string& why)
      : std::runtime_error(field + ": " + why), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

}  // namespace shadow
