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
#include <utility>
#include <vector>

#include "engine/cl/runtime.hpp"

namespace shadow::cl {

// Defined in the build-generated kernel_sources.cpp.
std::string_view kernel_source(std::string_view file_name);

// What a program is built from: kernels/prelude.cl, then `file_name`, each with its
// `#include "other.cl"` lines replaced by those files' texts (once each).
std::string expanded_source(std::string_view file_name);

// Appended to every program's build options when set, after the program's own (e.g. "-Werror"
// to see a new compiler's warnings as errors).
inline constexpr const char* kExtraOptionsVariable = "SHADOW_CL_OPTIONS";

class ProgramCache {
 public:
  // kWhereKnown: -DCLANG_CPU_BUILTINS where the device is known to take clang's builtins;
  // kNone: never, to build what every other compiler sees.
  enum class ClangBuiltins { kWhereKnown, kNone };
  explicit ProgramCache(const Device& device,
                        ClangBuiltins clang_builtins = ClangBuiltins::kWhereKnown);

  // The program of kernels/`file` built with `options` (e.g. "-DTILE=64"), built on first use.
  // Throws cl::Error with the build log when it does not compile. Thread-safe.
  cl_program program(std::string_view file, const std::string& options);

  size_t program_count() const;

  // What every program is built with on this device, before its own options (and
  // SHADOW_CL_OPTIONS after them):
  // - OpenCL C 1.2;
  // - -cl-fp32-correctly-rounded-divide-sqrt where the device supports it (by default float
  //   division and sqrt may be off by 2.5 and 3 ulp, differently on each device);
  // - -DCLANG_CPU_BUILTINS on PoCL's CPU devices, the one compiler known to take clang's own
  //   builtins (the kernels guard them with it: NVIDIA's refuses __builtin_prefetch).
  const std::string& common_options() const { return common_options_; }

  // Every (file, options) built by any ProgramCache of this process, in order: what the engine's
  // start-up compiled, for the tests that build it all again under stricter options.
  static std::vector<std::pair<std::string, std::string>> built_in_process();

 private:
  const Device& device_;
  std::string common_options_;
  std::string extra_options_;  // SHADOW_CL_OPTIONS
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
