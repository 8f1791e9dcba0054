#include "engine/cl/runtime.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <optional>

#include <unistd.h>

#include "wire/errors.hpp"
#include "wire/units.hpp"

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
  budget_bytes_ = memory_budget != 0 ? memory_budget : default_budget(global_mem_bytes_);
}

uint64_t Device::default_budget(uint64_t global_mem_bytes) {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return global_mem_bytes;
  const uint64_t half = uint64_t(pages) * uint64_t(page) / 2;
  // What the budget does not count stays within half the host too: the process' baseline
  // (programs, gRPC, heap; docs/usage.md, "Memory") is kept out of it.
  const uint64_t baseline = uint64_t{kBaselineMiB} << 20;
  const uint64_t host = half > 2 * baseline ? half - baseline : half / 2;
  return std::min(global_mem_bytes, host);
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
  if (err != CL_SUCCESS) counts_.allocated.fetch_sub(n);
  check(err, "clCreateBuffer");
  return Buffer(std::move(mem), n, &counts_);
}

void Device::take(uint64_t bytes, const std::string& what) const {
  // Counted only where it fits, in one compare-and-swap: a take that fails never shows in the
  // count, so it cannot make a concurrent one fail (requests waiting for memory try often).
  uint64_t before = counts_.allocated.load();
  while (bytes <= budget_bytes_ && before <= budget_bytes_ - bytes &&
         !counts_.allocated.compare_exchange_weak(before, before + bytes)) {
  }
  if (bytes > budget_bytes_ || before > budget_bytes_ - bytes) {
    throw ResourceExhausted(
        "memory_budget", "a " + what + " needs " + bytes_text(bytes) + " but " +
                             bytes_text(before) + " of the server's " + bytes_text(budget_bytes_) +
                             " memory budget (--memory-budget) are in use; use a smaller "
                             "request or retry when the server is less busy");
  }
}

Reservation Device::reserve(uint64_t bytes, const std::string& what) const {
  take(bytes, what);
  return Reservation(bytes, &counts_.allocated);
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
  const cl_uint pattern = value;
  // A fill of a large map holds the device as a slice does: it takes a turn.
  return in_turn([&](cl_event* e) {
    return clEnqueueFillBuffer(queue_.get(), dst.get(), &pattern, sizeof(pattern), 0,
                               dst.bytes() & ~size_t{3}, 0, nullptr, e);
  });
}

void Runtime::check_cancelled() const {
  if (progress_) progress_(own_ms_);
  if (cancelled_ && cancelled_()) {
    drain();
    throw Cancelled();
  }
  if (estimate_ms_ > 0 && own_work_ms_ > guard_ms(estimate_ms_, slack_ms_)) {
    drain();
    throw ResourceExhausted(
        "request cost",
        "the request has run " + ms_text(own_work_ms_) + " of device work, more than " +
            ms_text(guard_ms(estimate_ms_, slack_ms_)) + " (" + std::to_string(int(kGuardFactor)) +
            "x its admitted estimate of " + ms_text(estimate_ms_) + ", plus " + ms_text(slack_ms_) +
            "): it was stopped so that a wrong estimate cannot hold the device; "
            "ask for less");
  }
}

void Runtime::set_account(std::string client, double estimate_ms, double slack_ms) {
  client_ = std::move(client);
  estimate_ms_ = estimate_ms;
  slack_ms_ = slack_ms;
  own_ms_ = own_work_ms_ = 0;
}

void Runtime::charge(double ms) const {
  own_ms_ += ms;
  own_work_ms_ += ms * device_->core_share().sample();
}

template <class Enqueue>
Event Runtime::in_turn(Enqueue enqueue) const {
  DeviceTurns& turns = device_->turns();
  turns.take(client_, this);
  double ms = 0;
  Event event;
  try {
    cl_event e = nullptr;
    checked(enqueue(&e), "clEnqueue (in a turn)");
    event = Event(e);
    checked(clWaitForEvents(1, &e), "clWaitForEvents");
    ms = event_ms(event);
  } catch (...) {
    turns.give(client_, ms);
    throw;
  }
  turns.give(client_, ms);
  charge(ms);
  return event;
}

void Runtime::checked(cl_int code, const char* call) const {
  if (code == CL_SUCCESS) return;
  drain();
  throw Error(call, code);
}

Events Runtime::launch(cl_kernel kernel, size_t global, size_t local) const {
  Events events;
  const DeviceProfile& profile = device_->profile();
  DeviceTurns& turns = device_->turns();
  const size_t groups = (global + local - 1) / local;
  const size_t first = std::max<size_t>(1, profile.first_slice_groups);
  // A work-item's cost varies across the range (a view's sky rows cost nothing, its receivers
  // under a wide PCSS search a lot): a slice is sized by the dearest rate seen so far, grows at
  // most 4x, and a long range is cut in at least kMinSlices, so that cheap first rows do not
  // size a slice that lands on dear ones (a 1080p PCSS launch's second slice took 1 s).
  const size_t most = std::max(first, (groups + kMinSlices - 1) / kMinSlices);
  double ms_per_group = 0;
  size_t slice = first;
  // The slice enqueued last, still running: the next is enqueued behind it before it is waited
  // for (DeviceTurns lets a client queue a second command while it is ahead).
  struct Running {
    Event event;
    size_t groups = 0;
  };
  std::optional<Running> running;
  // Waits for the running slice, charges its time and sizes the next slice by its rate.
  const auto finish_running = [&] {
    cl_event e = running->event.get();
    double ms = 0;
    try {
      checked(clWaitForEvents(1, &e), "clWaitForEvents");
      ms = event_ms(running->event);
    } catch (...) {
      turns.give(client_, ms);
      running.reset();
      throw;
    }
    turns.give(client_, ms);
    charge(ms);
    ms_per_group = std::max(ms_per_group, ms / double(running->groups));
    const size_t count = running->groups;
    events.push_back(std::move(running->event));
    running.reset();
    const double fits = ms_per_group > 0 ? profile.slice_ms / ms_per_group : 4.0 * double(count);
    slice = size_t(std::clamp(fits, 1.0, std::min(4.0 * double(count), double(most))));
  };
  try {
    for (size_t done = 0; done < groups;) {
      check_cancelled();
      const size_t count = std::min(slice, groups - done);
      const size_t offset = done * local, items = count * local;
      // Behind the running slice if the device allows it now; else that one first, then a turn.
      if (!running || !turns.take_behind(client_, this)) {
        if (running) finish_running();
        turns.take(client_, this);
      }
      cl_event e = nullptr;
      const cl_int code =
          clEnqueueNDRangeKernel(queue_.get(), kernel, 1, &offset, &items, &local, 0, nullptr, &e);
      if (code != CL_SUCCESS) turns.give(client_, 0);
      checked(code, "clEnqueueNDRangeKernel");
      clFlush(queue_.get());
      done += count;
      if (running) finish_running();
      running = Running{Event(e), count};
    }
    if (running) finish_running();
  } catch (...) {
    if (running) {  // its turn goes back once it has run
      drain();
      turns.give(client_, 0);
    }
    throw;
  }
  return events;
}

void Runtime::finish() const {
  checked(clFinish(queue_.get()), "clFinish");
}

void Runtime::drain() const noexcept {
  // A queue that cannot finish (a lost device) has nothing left to run that could read memory.
  clFinish(queue_.get());
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
