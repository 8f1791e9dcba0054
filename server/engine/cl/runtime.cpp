#include "engine/cl/runtime.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "wire/errors.hpp"

namespace shadow::cl {

Error::Error(std::string call, cl_int code, std::string build_log)
    : std::runtime_error(call + " failed with OpenCL error " + std::to_string(code) +
                         (build_log.empty() ? "" : "\nbuild log:\n" + build_log)),
      call_(std::move(call)),
      code_(code),
      build_log_(std::move(build_log)) {}

namespace {

// PoCL reads POCL_CACHE_DIR when it initializes, so this must run before the first CL call.
void point_pocl_cache_at_persistent_dir() {
  if (std::getenv("POCL_CACHE_DIR")) return;
  std::filesystem::path base;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) {
    base = xdg;
  } else if (const char* home = std::getenv("HOME"); home && *home) {
    base = std::filesystem::path(home) / ".cache";
  } else {
    return;  // PoCL falls back to its own default
  }
  std::filesystem::path dir = base / "shadow-service" / "pocl";
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (!ec) setenv("POCL_CACHE_DIR", dir.c_str(), 0);
}

}  // namespace

Device::Device(uint64_t memory_budget, const std::string& spec, const std::string& profile) {
  point_pocl_cache_at_persistent_dir();
  const Inventory inventory = enumerate_devices();
  if (inventory.devices.empty())
    throw Error("clGetDeviceIDs (no OpenCL device on any platform)", CL_DEVICE_NOT_FOUND);
  const size_t chosen = choose_device(inventory.devices, resolve_device_spec(spec));
  device_ = inventory.ids[chosen];
  record_ = inventory.devices[chosen];

  // Named explicitly: with several platforms installed, the context must be the device's own.
  cl_platform_id platform = nullptr;
  check(clGetDeviceInfo(device_, CL_DEVICE_PLATFORM, sizeof platform, &platform, nullptr),
        "clGetDeviceInfo");
  const cl_context_properties properties[] = {CL_CONTEXT_PLATFORM, cl_context_properties(platform),
                                              0};
  cl_int err = CL_SUCCESS;
  context_ = Context(clCreateContext(properties, 1, &device_, nullptr, nullptr, &err));
  check(err, "clCreateContext");
  size_t max_group = 1;
  check(clGetDeviceInfo(device_, CL_DEVICE_MAX_WORK_GROUP_SIZE, sizeof max_group, &max_group,
                        nullptr),
        "clGetDeviceInfo");
  std::string setting;
  const std::string choice = resolve_profile_choice(profile, &setting);
  profile_ = make_profile(record_, max_group, choice, setting);
  max_alloc_bytes_ = record_.max_alloc_bytes;
  global_mem_bytes_ = record_.global_mem_bytes;
  budget_bytes_ = memory_budget != 0 ? memory_budget : global_mem_bytes_;
}

Buffer Device::alloc(size_t bytes, cl_mem_flags flags, Reservation* pledged) const {
  size_t n = bytes == 0 ? 16 : bytes;
  if (n > max_alloc_bytes_) {
    throw Error("clCreateBuffer (" + std::to_string(n) + " bytes exceeds the device's " +
                    std::to_string(max_alloc_bytes_) + "-byte buffer limit)",
                CL_INVALID_BUFFER_SIZE);
  }
  // The pledge pays what it can; the budget the rest (checked first: a refusal changes nothing).
  take(n - std::min<uint64_t>(n, pledged ? pledged->bytes() : 0), "device buffer");
  if (pledged) pledged->draw(n);
  cl_int err = CL_SUCCESS;
  Mem mem(clCreateBuffer(context_.get(), flags, n, nullptr, &err));
  if (err != CL_SUCCESS) allocated_.fetch_sub(n);
  check(err, "clCreateBuffer");
  return Buffer(std::move(mem), n, &allocated_);
}

void Device::take(uint64_t bytes, const std::string& what) const {
  // Counted only where it fits, in one compare-and-swap: a take that fails never shows in the
  // count, so it cannot make a concurrent one fail (requests waiting for memory try often).
  uint64_t before = allocated_.load();
  while (bytes <= budget_bytes_ && before <= budget_bytes_ - bytes &&
         !allocated_.compare_exchange_weak(before, before + bytes)) {
  }
  if (bytes > budget_bytes_ || before > budget_bytes_ - bytes) {
    throw ResourceExhausted("memory_budget",
                            "a " + std::to_string(bytes) + "-byte " + what + " would take the " +
                                std::to_string(before) + " bytes in use past the server's " +
                                std::to_string(budget_bytes_) +
                                "-byte memory budget (--memory-budget); use a smaller request or "
                                "retry when the server is less busy");
  }
}

Reservation Device::reserve(uint64_t bytes, const std::string& what) const {
  take(bytes, what);
  return Reservation(bytes, &allocated_);
}

Runtime::Runtime() : Runtime(std::make_shared<const Device>()) {}

Runtime::Runtime(std::shared_ptr<const Device> device) : device_(std::move(device)) {
  cl_int err = CL_SUCCESS;
  cl_device_id d = device_->device();
  queue_ = Queue(clCreateCommandQueue(device_->context(), d, CL_QUEUE_PROFILING_ENABLE, &err));
  check(err, "clCreateCommandQueue");
}

Buffer Runtime::alloc(size_t bytes, cl_mem_flags flags) const {
  try {
    return device_->alloc(bytes, flags, &pledge_);
  } catch (...) {
    drain();
    throw;
  }
}

void Runtime::ensure(Buffer& b, size_t bytes) const {
  if (b.bytes() >= bytes && b.get()) return;
  b = Buffer();  // release first, so old and new never coexist
  const uint64_t roomy = grown(bytes);
  b = alloc(roomy <= max_alloc_bytes() ? roomy : bytes);
}

Event Runtime::write(const Buffer& dst, const void* src, size_t bytes, size_t offset) const {
  cl_event e = nullptr;
  if (bytes == 0) return Event();
  checked(
      clEnqueueWriteBuffer(queue_.get(), dst.get(), CL_FALSE, offset, bytes, src, 0, nullptr, &e),
      "clEnqueueWriteBuffer");
  return Event(e);
}

Event Runtime::read(const Buffer& src, void* dst, size_t bytes, size_t offset) const {
  cl_event e = nullptr;
  if (bytes == 0) return Event();
  check_cancelled();
  checked(clEnqueueReadBuffer(queue_.get(), src.get(), CL_TRUE, offset, bytes, dst, 0, nullptr, &e),
          "clEnqueueReadBuffer");
  return Event(e);
}

Event Runtime::fill_zero(const Buffer& dst) const {
  return fill(dst, 0);
}

Event Runtime::fill(const Buffer& dst, uint32_t value) const {
  cl_event e = nullptr;
  const cl_uint pattern = value;
  checked(clEnqueueFillBuffer(queue_.get(), dst.get(), &pattern, sizeof(pattern), 0,
                              dst.bytes() & ~size_t{3}, 0, nullptr, &e),
          "clEnqueueFillBuffer");
  return Event(e);
}

void Runtime::check_cancelled() const {
  if (cancelled_ && cancelled_()) {
    drain();
    throw Cancelled();
  }
}

void Runtime::checked(cl_int code, const char* call) const {
  if (code == CL_SUCCESS) return;
  drain();
  throw Error(call, code);
}

Events Runtime::launch(cl_kernel kernel, size_t global, size_t local) const {
  Events events;
  const size_t rounded = (global + local - 1) / local * local;
  const size_t items = device_->profile().slice_items;
  const size_t slice = std::max(local, items / local * local);
  for (size_t offset = 0; offset < rounded; offset += slice) {
    // Throttle: wait for the slice before last, then ask whether to go on.
    while (in_flight_.size() >= 2) {
      cl_event oldest = in_flight_.front().get();
      checked(clWaitForEvents(1, &oldest), "clWaitForEvents");
      in_flight_.pop_front();
    }
    check_cancelled();
    const size_t count = std::min(slice, rounded - offset);
    cl_event e = nullptr;
    checked(
        clEnqueueNDRangeKernel(queue_.get(), kernel, 1, &offset, &count, &local, 0, nullptr, &e),
        "clEnqueueNDRangeKernel");
    checked(clRetainEvent(e), "clRetainEvent");
    in_flight_.emplace_back(e);
    events.emplace_back(e);
  }
  return events;
}

void Runtime::finish() const {
  checked(clFinish(queue_.get()), "clFinish");
  in_flight_.clear();
}

void Runtime::drain() const noexcept {
  // A queue that cannot finish (a lost device) has nothing left to run that could read memory.
  clFinish(queue_.get());
  in_flight_.clear();
}

double event_ms(const Event& e) {
  if (!e) return 0.0;
  cl_ulong start = 0, end = 0;
  check(
      clGetEventProfilingInfo(e.get(), CL_PROFILING_COMMAND_START, sizeof(start), &start, nullptr),
      "clGetEventProfilingInfo");
  check(clGetEventProfilingInfo(e.get(), CL_PROFILING_COMMAND_END, sizeof(end), &end, nullptr),
        "clGetEventProfilingInfo");
  return double(end - start) * 1e-6;
}

}  // namespace shadow::cl
