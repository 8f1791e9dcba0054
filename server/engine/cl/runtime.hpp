// A thin RAII layer over the OpenCL C API: handles, buffers, launches and profiling events.
// One Runtime owns the PoCL device, its context and one in-order profiling queue.
#pragma once

#include <CL/cl.h>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shadow::cl {

// A failed OpenCL call: which call, its error code and, for builds, the compiler's log.
class Error : public std::runtime_error {
 public:
  Error(std::string call, cl_int code, std::string build_log = {});
  const std::string& call() const { return call_; }
  cl_int code() const { return code_; }
  const std::string& build_log() const { return build_log_; }

 private:
  std::string call_;
  cl_int code_;
  std::string build_log_;
};

inline void check(cl_int code, const char* call) {
  if (code != CL_SUCCESS) throw Error(call, code);
}

// Owns one reference to an OpenCL object.
template <typename T, cl_int (*Release)(T)>
class Handle {
 public:
  Handle() = default;
  explicit Handle(T raw) : raw_(raw) {}
  Handle(Handle&& o) noexcept : raw_(std::exchange(o.raw_, nullptr)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      raw_ = std::exchange(o.raw_, nullptr);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }

  T get() const { return raw_; }
  explicit operator bool() const { return raw_ != nullptr; }
  void reset() {
    if (raw_) Release(raw_);
    raw_ = nullptr;
  }

 private:
  T raw_ = nullptr;
};

using Context = Handle<cl_context, clReleaseContext>;
using Queue = Handle<cl_command_queue, clReleaseCommandQueue>;
using Program = Handle<cl_program, clReleaseProgram>;
using Kernel = Handle<cl_kernel, clReleaseKernel>;
using Mem = Handle<cl_mem, clReleaseMemObject>;
using Event = Handle<cl_event, clReleaseEvent>;

// A device buffer that knows its size in bytes.
class Buffer {
 public:
  Buffer() = default;
  Buffer(Mem mem, size_t bytes) : mem_(std::move(mem)), bytes_(bytes) {}
  cl_mem get() const { return mem_.get(); }
  size_t bytes() const { return bytes_; }

 private:
  Mem mem_;
  size_t bytes_ = 0;
};

// Kernel arguments: buffers by handle, everything else by value (must match the .cl types).
inline void set_arg(cl_kernel k, cl_uint i, const Buffer& b) {
  cl_mem m = b.get();
  check(clSetKernelArg(k, i, sizeof(cl_mem), &m), "clSetKernelArg");
}
template <typename T>
void set_arg(cl_kernel k, cl_uint i, const T& value) {
  static_assert(std::is_trivially_copyable_v<T>);
  check(clSetKernelArg(k, i, sizeof(T), &value), "clSetKernelArg");
}
template <typename... Args>
void set_args(cl_kernel k, const Args&... args) {
  cl_uint i = 0;
  (set_arg(k, i++, args), ...);
}

class Runtime {
 public:
  Runtime();  // first PoCL (else first) device; points PoCL's kernel cache at a persistent dir

  cl_context context() const { return context_.get(); }
  cl_device_id device() const { return device_; }
  cl_command_queue queue() const { return queue_.get(); }
  const std::string& device_name() const { return device_name_; }
  uint64_t max_alloc_bytes() const { return max_alloc_bytes_; }
  uint64_t global_mem_bytes() const { return global_mem_bytes_; }

  // Allocation checks the device's per-buffer limit first. A zero-byte request allocates one
  // element, so empty inputs still bind a valid buffer.
  Buffer alloc(size_t bytes, cl_mem_flags flags = CL_MEM_READ_WRITE) const;
  // Grow-only scratch: reallocates `b` only when it holds fewer than `bytes`. Reusing buffers
  // across requests spares the page faults of touching fresh memory (~1 ms per 4 MB here).
  void ensure(Buffer& b, size_t bytes) const;
  Event write(const Buffer& dst, const void* src, size_t bytes, size_t offset = 0) const;
  Event read(const Buffer& src, void* dst, size_t bytes, size_t offset = 0) const;
  Event fill_zero(const Buffer& dst) const;
  // Enqueues a 1-D NDRange of `global` work-items with a fixed local size.
  Event launch(cl_kernel kernel, size_t global, size_t local = 1) const;
  void finish() const;

  template <typename T>
  Buffer upload(const std::vector<T>& v, std::vector<Event>* events = nullptr) const {
    Buffer b = alloc(v.size() * sizeof(T), CL_MEM_READ_ONLY);
    Event e = write(b, v.data(), v.size() * sizeof(T));
    if (events) events->push_back(std::move(e));
    return b;
  }

 private:
  cl_device_id device_ = nullptr;
  Context context_;
  Queue queue_;
  std::string device_name_;
  uint64_t max_alloc_bytes_ = 0;
  uint64_t global_mem_bytes_ = 0;
};

// Device time of a finished event in milliseconds (profiling queue).
double event_ms(const Event& e);

}  // namespace shadow::cl
