#include "engine/cl/program_cache.hpp"

#include <cstdint>
#include <cstdio>

namespace shadow::cl {
namespace {

uint64_t fnv1a(std::string_view s) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

std::string build_log(cl_program p, cl_device_id d) {
  size_t n = 0;
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n);
  std::string log(n, '\0');
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, n, log.data(), nullptr);
  return log;
}

}  // namespace

ProgramCache::Entry& ProgramCache::program(std::string_view file, const std::string& options) {
  std::string source(kernel_source("prelude.cl"));
  source += "\n#line 1\n";
  source += kernel_source(file);
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a(source)));
  std::string key = std::string(hash) + "|" + options;
  if (auto it = programs_.find(key); it != programs_.end()) return it->second;

  const char* text = source.c_str();
  size_t length = source.size();
  cl_int err = CL_SUCCESS;
  Program prog(clCreateProgramWithSource(runtime_.context(), 1, &text, &length, &err));
  check(err, "clCreateProgramWithSource");
  cl_device_id device = runtime_.device();
  std::string all_options = "-cl-std=CL1.2 " + options;
  err = clBuildProgram(prog.get(), 1, &device, all_options.c_str(), nullptr, nullptr);
  if (err != CL_SUCCESS) {
    throw Error("clBuildProgram(" + std::string(file) + ", \"" + options + "\")", err,
                build_log(prog.get(), device));
  }
  return programs_.emplace(key, Entry{std::move(prog), {}}).first->second;
}

cl_kernel ProgramCache::kernel(std::string_view file, const std::string& name,
                               const std::string& options) {
  Entry& entry = program(file, options);
  auto it = entry.kernels.find(name);
  if (it == entry.kernels.end()) {
    cl_int err = CL_SUCCESS;
    Kernel k(clCreateKernel(entry.program.get(), name.c_str(), &err));
    if (err != CL_SUCCESS) throw Error("clCreateKernel(" + name + ")", err);
    it = entry.kernels.emplace(name, std::move(k)).first;
  }
  return it->second.get();
}

}  // namespace shadow::cl
