// A thin RAII layer over the OpenCL C API: handles, buffers, launches and profiling events.
// One Device (the chosen OpenCL device, its context and the device-memory budget) is shared by
// every Runtime; each Runtime is one request's in-order profiling queue on it.
#pragma once

#include <CL/cl.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "engine/cl/core_share.hpp"
#include "engine/cl/device_choice.hpp"
#include "engine/cl/device_profile.hpp"
#include "engine/cl/device_turns.hpp"

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

// What a Device counts: every buffer and reservation against the budget, and its buffers alone
// with their peak (what the memory estimates are measured against).
struct Counts {
  std::atomic<uint64_t> allocated{0};  // buffers and reservations
  std::atomic<uint64_t> buffers{0};
  std::atomic<uint64_t> buffer_peak{0};
};

// A device buffer that knows its size in bytes and gives them back to its Device's counts when
// it is released.
class Buffer {
 public:
  Buffer() = default;
  Buffer(Mem mem, size_t bytes, Counts* counted)
      : mem_(std::move(mem)), bytes_(bytes), counted_(counted) {
    const uint64_t now = counted_->buffers.fetch_add(bytes_) + bytes_;
    uint64_t peak = counted_->buffer_peak.load();
    while (now > peak && !counted_->buffer_peak.compare_exchange_weak(peak, now)) {
    }
  }
  Buffer(Buffer&& o) noexcept
      : mem_(std::move(o.mem_)),
        bytes_(std::exchange(o.bytes_, 0)),
        counted_(std::exchange(o.counted_, nullptr)) {}
  Buffer& operator=(Buffer&& o) noexcept {
    if (this != &o) {
      release();
      mem_ = std::move(o.mem_);
      bytes_ = std::exchange(o.bytes_, 0);
      counted_ = std::exchange(o.counted_, nullptr);
    }
    return *this;
  }
  ~Buffer() { release(); }
  cl_mem get() const { return mem_.get(); }
  size_t bytes() const { return bytes_; }

 private:
  void release() {
    mem_.reset();
    if (counted_) {
      counted_->allocated.fetch_sub(bytes_);
      counted_->buffers.fetch_sub(bytes_);
    }
    counted_ = nullptr;
    bytes_ = 0;
  }
  Mem mem_;
  size_t bytes_ = 0;
  Counts* counted_ = nullptr;
};

using Events = std::vector<Event>;

// Bytes held against a Device's budget that are not a device buffer (a reply being streamed, a
// request waiting for a workspace); given back when it goes.
class Reservation {
 public:
  Reservation() = default;
  Reservation(uint64_t bytes, std::atomic<uint64_t>* counted) : bytes_(bytes), counted_(counted) {}
  Reservation(Reservation&& o) noexcept
      : bytes_(std::exchange(o.bytes_, 0)), counted_(std::exchange(o.counted_, nullptr)) {}
  Reservation& operator=(Reservation&& o) noexcept {
    if (this != &o) {
      release();
      bytes_ = std::exchange(o.bytes_, 0);
      counted_ = std::exchange(o.counted_, nullptr);
    }
    return *this;
  }
  ~Reservation() { release(); }
  uint64_t bytes() const { return bytes_; }
  // Hands up to `n` of these bytes to a buffer that counts them from now on (so they are not
  // counted twice); returns how many.
  uint64_t draw(uint64_t n) {
    const uint64_t drawn = std::min(n, bytes_);
    bytes_ -= drawn;
    return drawn;
  }

 private:
  void release() {
    if (counted_) counted_->fetch_sub(bytes_);
    counted_ = nullptr;
    bytes_ = 0;
  }
  uint64_t bytes_ = 0;
  std::atomic<uint64_t>* counted_ = nullptr;
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

// The OpenCL device and its context. Every buffer allocated on it and every Reservation counts
// against one budget, so concurrent requests, their device buffers and their replies together
// stay inside the memory the server may use (PoCL's device memory is host memory).
class Device {
 public:
  // The device `spec` picks, else $SHADOW_DEVICE's, else the default (engine/cl/device_choice.hpp:
  // a GPU, else a CPU device); DeviceChoiceError when the SPEC names none. Points PoCL's kernel
  // cache at a persistent dir. A budget of 0 is the device's global memory.
  // `profile` picks the kernels' shape (engine/cl/device_profile.hpp: cpu, gpu or auto; empty:
  // $SHADOW_KERNEL_PROFILE, else auto).
  explicit Device(uint64_t memory_budget = 0, const std::string& spec = {},
                  const std::string& profile = {});
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  cl_context context() const { return context_.get(); }
  cl_device_id device() const { return device_; }
  const DeviceRecord& record() const { return record_; }  // names, type, driver, limits
  const DeviceProfile& profile() const { return profile_; }
  const std::string& device_name() const { return record_.device_name; }
  uint64_t max_alloc_bytes() const { return max_alloc_bytes_; }
  uint64_t global_mem_bytes() const { return global_mem_bytes_; }
  uint64_t budget_bytes() const { return budget_bytes_; }
  uint64_t allocated_bytes() const { return counts_.allocated.load(); }  // buffers, reservations
  // The most bytes of buffers alone held at once since the last reset_buffer_peak() (benches and
  // the memory-estimate tests).
  uint64_t buffer_peak_bytes() const { return counts_.buffer_peak.load(); }
  void reset_buffer_peak() const { counts_.buffer_peak.store(counts_.buffers.load()); }

  // Checks the per-buffer limit (cl::Error) and the budget (ResourceExhausted naming it) before
  // allocating. A zero-byte request allocates one element, so empty inputs still bind a buffer.
  // Bytes `pledged` to the caller beforehand pay for the buffer while they last.
  Buffer alloc(size_t bytes, cl_mem_flags flags = CL_MEM_READ_WRITE,
               Reservation* pledged = nullptr) const;
  // `bytes` of the budget for `what` (e.g. "the reply"); ResourceExhausted naming the budget.
  Reservation reserve(uint64_t bytes, const std::string& what) const;
  // Turns on the device, one launch slice at a time, shared fairly between clients.
  DeviceTurns& turns() const { return turns_; }
  // The share of a CPU device's time its worker threads ran (1 until the engine names them).
  CoreShare& core_share() const { return core_share_; }
  // The default memory budget: the smaller of the device's global memory and half the host's
  // (PoCL reports all of the host's RAM as a CPU device's global memory; issue 51).
  static uint64_t default_budget(uint64_t global_mem_bytes);
  static constexpr uint64_t kBaselineMiB = 512;

 private:
  // Counts `bytes` in or throws; `what` names them in the error.
  void take(uint64_t bytes, const std::string& what) const;

  cl_device_id device_ = nullptr;
  Context context_;
  DeviceRecord record_;
  DeviceProfile profile_;
  uint64_t max_alloc_bytes_ = 0;
  uint64_t global_mem_bytes_ = 0;
  uint64_t budget_bytes_ = 0;
  mutable CoreShare core_share_;
  mutable Counts counts_;
  mutable DeviceTurns turns_;
};

// One in-order profiling queue on a shared Device: the commands of one request. Not
// thread-safe; each concurrent request has its own.
//
// Writes are asynchronous and read their host memory when the device gets to them, so every
// exception that leaves a Runtime call (a cancel, a full budget, a failed enqueue) first drains
// the queue: the unwinding may free that memory. Host memory given to write() must otherwise
// live until the next blocking read() or finish().
class Runtime {
 public:
  Runtime();  // on a Device of its own (tests, benches)
  explicit Runtime(std::shared_ptr<const Device> device);

  const Device& device_info() const { return *device_; }
  cl_context context() const { return device_->context(); }
  cl_device_id device() const { return device_->device(); }
  cl_command_queue queue() const { return queue_.get(); }
  const std::string& device_name() const { return device_->device_name(); }
  uint64_t max_alloc_bytes() const { return device_->max_alloc_bytes(); }
  uint64_t global_mem_bytes() const { return device_->global_mem_bytes(); }

  Buffer alloc(size_t bytes, cl_mem_flags flags = CL_MEM_READ_WRITE) const;
  // Grow-only scratch: reallocates `b` only when it holds fewer than `bytes`, then with
  // headroom (grown()). Reusing buffers across requests spares the page faults of touching
  // fresh memory (~1 ms per 4 MB here).
  void ensure(Buffer& b, size_t bytes) const;
  // What ensure() allocates for `bytes` (where the device allows): a quarter more, so a
  // slightly larger request does not reallocate.
  static uint64_t grown(uint64_t bytes) { return bytes + bytes / 4; }
  Event write(const Buffer& dst, const void* src, size_t bytes, size_t offset = 0) const;
  Event read(const Buffer& src, void* dst, size_t bytes, size_t offset = 0) const;
  Event fill_zero(const Buffer& dst) const;
  // Every whole 32-bit word of `dst` set to `value`.
  Event fill(const Buffer& dst, uint32_t value) const;
  // Runs a 1-D NDRange of `global` work-items with a fixed local size, in slices (global
  // offsets; kernels index by get_global_id only), each in a turn of the device's
  // (DeviceTurns): only this client's slices run meanwhile, the next queued behind the one
  // running while the client is ahead. Slices start at one work-group per compute unit and
  // grow, at most 4x a slice and to at most 1/kMinSlices of the range, to the work-items that
  // the dearest rate measured so far puts at the profile's slice_ms, so that no slice holds the
  // device long whatever a work-item costs, and a cancel stops within one or two.
  Events launch(cl_kernel kernel, size_t global, size_t local = 1) const;
  static constexpr size_t kMinSlices = 32;
  void finish() const;
  // finish() that never throws, for paths already unwinding: waits for every command enqueued.
  void drain() const noexcept;

  // Asked before every launch and read; when it says yes, they throw shadow::Cancelled.
  // Empty: never cancelled.
  void set_cancelled(std::function<bool()> cancelled) { cancelled_ = std::move(cancelled); }
  // Told the queue's own device ms (own_ms()) at the same points, on the thread that launches:
  // how far the request is. Empty: nothing.
  void set_progress(std::function<void(double own_ms)> progress) {
    progress_ = std::move(progress);
  }
  // Budget set aside for this queue's request when it was admitted: its new buffers draw on it
  // before they take from the budget, so requests admitted side by side cannot take each
  // other's memory. What is left goes back with the next pledge (or an empty one).
  void set_pledge(Reservation pledge) { pledge_ = std::move(pledge); }
  // Whom the queue's device time is charged to (DeviceTurns), and the guard against a wrong
  // estimate: once its own device work since this call passes guard_ms(`estimate_ms`,
  // `slack_ms`), the next launch throws ResourceExhausted naming both (0: no guard). An empty
  // client is one like any other.
  void set_account(std::string client, double estimate_ms = 0, double slack_ms = kGuardSlackMs);
  // 3x the estimate, plus 2 s: for the launches' fixed costs, which the linear cost model leaves
  // out (a 2 ms request may take 6 ms), so that only a long wrong estimate is stopped. The guard
  // counts device work, not device time: on a CPU device whose cores other processes share, a
  // launch's time stretches with their load (CoreShare), and a right estimate must not be
  // stopped for it.
  static constexpr double kGuardFactor = 3, kGuardSlackMs = 2000;
  static double guard_ms(double estimate_ms, double slack_ms = kGuardSlackMs) {
    return kGuardFactor * estimate_ms + slack_ms;
  }
  // Raises the admitted estimate by what the render learned on the device (a raster's overlaps
  // after binning); nothing without a guard.
  void add_to_estimate(double ms) const {
    if (estimate_ms_ > 0) estimate_ms_ += ms;
  }
  // Device ms of this queue's launches and fills since set_account (each slice's own time: they
  // run alone), and the part of it the device's threads ran (CoreShare).
  double own_ms() const { return own_ms_; }
  double own_work_ms() const { return own_work_ms_; }

  template <typename T>
  Buffer upload(const std::vector<T>& v, std::vector<Event>* events = nullptr) const {
    Buffer b = alloc(v.size() * sizeof(T), CL_MEM_READ_ONLY);
    Event e = write(b, v.data(), v.size() * sizeof(T));
    if (events) events->push_back(std::move(e));
    return b;
  }

 private:
  void check_cancelled() const;
  // Adds a launch's or fill's device ms to own_ms_, and its work to own_work_ms_.
  void charge(double ms) const;
  // check() for this queue's calls: drains before it throws.
  void checked(cl_int code, const char* call) const;
  // Runs one command that `enqueue` enqueues (its event) in a turn of the device's, waits for
  // it and charges its time; returns its event.
  template <class Enqueue>
  Event in_turn(Enqueue enqueue) const;

  std::shared_ptr<const Device> device_;
  Queue queue_;
  std::function<bool()> cancelled_;
  mutable Reservation pledge_;
  std::string client_;
  mutable double estimate_ms_ = 0;
  double slack_ms_ = kGuardSlackMs;
  std::function<void(double)> progress_;
  mutable double own_ms_ = 0;
  mutable double own_work_ms_ = 0;
};

// Device time of a finished event in milliseconds (profiling queue).
double event_ms(const Event& e);

}  // namespace shadow::cl
