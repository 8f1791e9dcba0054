// Builds OpenCL programs from the embedded kernels/*.cl (each prefixed with kernels/prelude.cl)
// once per (source, build options), shared by every request; and Kernels, one request's own
// cl_kernel objects made from them (clSetKernelArg state is per kernel object, so concurrent
// requests must not share one).
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <tuple>

#include "engine/cl/runtime.hpp"

namespace shadow::cl {

// Defined in the build-generated kernel_sources.cpp.
std::string_view kernel_source(std::string_view file_name);

class ProgramCache {
 public:
  explicit ProgramCache(const Device& device) : device_(device) {}

  // The program of kernels/`file` built with `options` (e.g. "-DTILE=64"), built on first use.
  // Throws cl::Error with the build log when it does not compile. Thread-safe.
  cl_program program(std::string_view file, const std::string& options);

  size_t program_count() const;

 private:
  const Device& device_;
  mutable std::mutex mutex_;
  // By (file, options); each file's source hash is computed once, when it is first built.
  std::map<std::pair<std::string, std::string>, Program> programs_;
};

// One request's (one Runtime's) kernel objects, created on first use from shared programs.
class Kernels {
 public:
  explicit Kernels(ProgramCache& programs) : programs_(&programs) {}
  // With a program cache of its own (tests and benches that run one queue).
  explicit Kernels(const Runtime& runtime)
      : own_(std::make_unique<ProgramCache>(runtime.device_info())), programs_(own_.get()) {}

  // The kernel `name` of kernels/`file` built with `options`.
  cl_kernel kernel(std::string_view file, const std::string& name, const std::string& options = "");

  ProgramCache& programs() { return *programs_; }

 private:
  std::unique_ptr<ProgramCache> own_;
  ProgramCache* programs_;
  std::map<std::tuple<std::string, std::string, std::string>, Kernel> kernels_;
};

}  // namespace shadow::cl
