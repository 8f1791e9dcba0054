#include "engine/cl/program_cache.hpp"

#include <cstdlib>
#include <set>

namespace shadow::cl {
namespace {

std::string platform_name(cl_device_id d) {
  cl_platform_id platform = nullptr;
  check(clGetDeviceInfo(d, CL_DEVICE_PLATFORM, sizeof platform, &platform, nullptr),
        "clGetDeviceInfo");
  size_t n = 0;
  check(clGetPlatformInfo(platform, CL_PLATFORM_NAME, 0, nullptr, &n), "clGetPlatformInfo");
  std::string name(n, '\0');
  check(clGetPlatformInfo(platform, CL_PLATFORM_NAME, n, name.data(), nullptr),
        "clGetPlatformInfo");
  return name;
}

std::string device_options(cl_device_id d, ProgramCache::ClangBuiltins clang_builtins) {
  std::string options = "-cl-std=CL1.2";
  cl_device_fp_config fp = 0;
  check(clGetDeviceInfo(d, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp, nullptr), "clGetDeviceInfo");
  if (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT)
    options += " -cl-fp32-correctly-rounded-divide-sqrt";
  cl_device_type type = 0;
  check(clGetDeviceInfo(d, CL_DEVICE_TYPE, sizeof type, &type, nullptr), "clGetDeviceInfo");
  if (clang_builtins == ProgramCache::ClangBuiltins::kWhereKnown && (type & CL_DEVICE_TYPE_CPU) &&
      platform_name(d).find("Portable Computing Language") != std::string::npos)
    options += " -DCLANG_CPU_BUILTINS";
  return options;
}

std::mutex built_mutex;
std::vector<std::pair<std::string, std::string>>& built_list() {
  static std::vector<std::pair<std::string, std::string>> built;
  return built;
}

std::string build_log(cl_program p, cl_device_id d) {
  size_t n = 0;
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n);
  std::string log(n, '\0');
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, n, log.data(), nullptr);
  return log;
}

// `file`'s text with each `#include "other.cl"` line replaced by that embedded file's text (itself
// expanded), between #line markers so that build logs name the right lines. A family's shared
// definitions live in one file that its CPU and GPU kernel files both include (issue 42). Each
// file is included at most once per program, as if every one had an include guard.
void append_expanded(std::string_view file, std::set<std::string>& seen, std::string& out) {
  if (!seen.insert(std::string(file)).second) return;
  const std::string_view text = kernel_source(file);
  constexpr std::string_view kInclude = "#include \"";
  size_t line_no = 1, at = 0;
  while (at < text.size()) {
    size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(at, end - at);
    const size_t close = line.rfind('"');
    if (line.substr(0, kInclude.size()) == kInclude && close > kInclude.size()) {
      append_expanded(line.substr(kInclude.size(), close - kInclude.size()), seen, out);
      out += "#line " + std::to_string(line_no + 1) + "\n";
    } else {
      out.append(line);
      out += '\n';
    }
    ++line_no;
    at = end + 1;
  }
}

}  // namespace

std::string expanded_source(std::string_view file) {
  std::set<std::string> seen;
  std::string source;
  append_expanded("prelude.cl", seen, source);
  source += "#line 1\n";
  append_expanded(file, seen, source);
  return source;
}

ProgramCache::ProgramCache(const Device& device, ClangBuiltins clang_builtins)
    : device_(device), common_options_(device_options(device.device(), clang_builtins)) {
  if (const char* extra = std::getenv(kExtraOptionsVariable)) extra_options_ = extra;
}

std::vector<std::pair<std::string, std::string>> ProgramCache::built_in_process() {
  std::lock_guard<std::mutex> lock(built_mutex);
  return built_list();
}

cl_program ProgramCache::program(std::string_view file, const std::string& options) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto key = std::make_pair(std::string(file), options);
  if (auto it = programs_.find(key); it != programs_.end()) return it->second.get();

  // The sources are embedded at build time, so (file, options) names one source text; PoCL's
  // own cache keys the compiled binary by the text's hash.
  const std::string source = expanded_source(file);
  const char* text = source.c_str();
  size_t length = source.size();
  cl_int err = CL_SUCCESS;
  Program prog(clCreateProgramWithSource(device_.context(), 1, &text, &length, &err));
  check(err, "clCreateProgramWithSource");
  cl_device_id device = device_.device();
  const std::string all_options = common_options_ + " " + options + " " + extra_options_;
  err = clBuildProgram(prog.get(), 1, &device, all_options.c_str(), nullptr, nullptr);
  if (err != CL_SUCCESS) {
    throw Error("clBuildProgram(" + std::string(file) + ", \"" + all_options + "\")", err,
                build_log(prog.get(), device));
  }
  {
    std::lock_guard<std::mutex> built_lock(built_mutex);
    built_list().push_back(key);
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
