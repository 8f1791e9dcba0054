// Builds OpenCL programs from the embedded kernels/*.cl (each prefixed with kernels/prelude.cl)
// once per (source hash, build options) and hands out their kernels.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <unordered_map>

#include "engine/cl/runtime.hpp"

namespace shadow::cl {

// Defined in the build-generated kernel_sources.cpp.
std::string_view kernel_source(std::string_view file_name);

class ProgramCache {
 public:
  explicit ProgramCache(const Runtime& runtime) : runtime_(runtime) {}

  // The kernel `name` of kernels/`file` built with `options` (e.g. "-DTILE=64"). Throws
  // cl::Error with the build log when the program does not compile.
  cl_kernel kernel(std::string_view file, const std::string& name, const std::string& options = "");

  size_t program_count() const { return programs_.size(); }

 private:
  struct Entry {
    Program program;
    std::map<std::string, Kernel> kernels;
  };
  Entry& program(std::string_view file, const std::string& options);

  const Runtime& runtime_;
  std::unordered_map<std::string, Entry> programs_;
};

}  // namespace shadow::cl
