#include "service/status.hpp"

#include <exception>
#include <iostream>
#include <new>

#include "wire/errors.hpp"

namespace shadow::service {

grpc::Status status_from_current_exception() {
  try {
    throw;
  } catch (const InvalidArgument& e) {
    // what() is "field: why", so clients can match the field path at the start.
    return {grpc::StatusCode::INVALID_ARGUMENT, e.what()};
  } catch (const ResourceExhausted& e) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED, e.what()};
  } catch (const NotFound& e) {
    return {grpc::StatusCode::NOT_FOUND, e.what()};
  } catch (const std::bad_alloc&) {
    std::cerr << "shadow-server: out of host memory while serving a request\n";
    return {grpc::StatusCode::RESOURCE_EXHAUSTED, "the server ran out of host memory"};
  } catch (const std::exception& e) {
    std::cerr << "shadow-server: internal error: " << e.what() << '\n';
    return {grpc::StatusCode::INTERNAL, std::string("internal error: ") + e.what()};
  } catch (...) {
    std::cerr << "shadow-server: internal error of unknown type\n";
    return {grpc::StatusCode::INTERNAL, "internal error"};
  }
}

}  // namespace shadow::service
