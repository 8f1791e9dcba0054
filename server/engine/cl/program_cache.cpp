#include "engine/cl/program_cache.hpp"

namespace shadow::cl {
namespace {

std::string build_log(cl_program p, cl_device_id d) {
  size_t n = 0;
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n);
  std::string log(n, '\0');
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, n, log.data(), nullptr);
  return log;
}

}  // namespace

cl_program ProgramCache::program(std::string_view file, const std::string& options) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto key = std::make_pair(std::string(file), options);
  if (auto it = programs_.find(key); it != programs_.end()) return it->second.get();

  // The sources are embedded at build time, so (file, options) names one source text; PoCL's
  // own cache keys the compiled binary by the text's hash.
  std::string source(kernel_source("prelude.cl"));
  source += "\n#line 1\n";
  source += kernel_source(file);
  const char* text = source.c_str();
  size_t length = source.size();
  cl_int err = CL_SUCCESS;
  Program prog(clCreateProgramWithSource(device_.context(), 1, &text, &length, &err));
  check(err, "clCreateProgramWithSource");
  cl_device_id device = device_.device();
  std::string all_options = "-cl-std=CL1.2 " + options;
  err = clBuildProgram(prog.get(), 1, &device, all_options.c_str(), nullptr, nullptr);
  if (err != CL_SUCCESS) {
    throw Error("clBuildProgram(" + std::string(file) + ", \"" + options + "\")", err,
                build_log(prog.get(), device));
  }
  return programs_.emplace(std::move(key), std::move(prog)).first->second.get();
}

size_t ProgramCache::program_count() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return programs_.size();
}

cl_kernel Kernels::kernel(std::string_view file, const std::string& name,
                          const std::string& options) {
  auto key = std::make_tuple(std::string(file), name, options);
  auto it = kernels_.find(key);
  if (it == kernels_.end()) {
    cl_int err = CL_SUCCESS;
    Kernel k(clCreateKernel(programs_->program(file, options), name.c_str(), &err));
    if (err != CL_SUCCESS) throw Error("clCreateKernel(" + name + ")", err);
    it = kernels_.emplace(std::move(key), std::move(k)).first;
  }
  return it->second.get();
}

}  // namespace shadow::cl
