// The runtime's promise to its callers (issue 40): an exception that leaves a Runtime call finds
// the queue drained, so the unwinding may free the host memory that an asynchronous write was
// still to read. The queue is held behind a user event that opens only after the exception would
// have been thrown, so a runtime that throws without draining leaves the write unfinished.
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "engine/cl/runtime.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

// A write queued behind a closed gate; the gate opens `delay` after construction.
struct HeldWrite {
  HeldWrite(const cl::Runtime& rt, std::chrono::milliseconds delay) : host(1 << 16, 1.0f) {
    cl_int err = CL_SUCCESS;
    gate = cl::Event(clCreateUserEvent(rt.context(), &err));
    cl::check(err, "clCreateUserEvent");
    cl_event raw = gate.get();
    cl::check(clEnqueueBarrierWithWaitList(rt.queue(), 1, &raw, nullptr), "barrier");
    buffer = rt.alloc(host.size() * sizeof(float));
    write = rt.write(buffer, host.data(), host.size() * sizeof(float));
    opener = std::thread([this, delay] {
      std::this_thread::sleep_for(delay);
      clSetUserEventStatus(gate.get(), CL_COMPLETE);
    });
  }
  ~HeldWrite() { opener.join(); }

  cl_int write_status() const {
    cl_int status = 0;
    cl::check(clGetEventInfo(write.get(), CL_EVENT_COMMAND_EXECUTION_STATUS, sizeof status, &status,
                             nullptr),
              "clGetEventInfo");
    return status;
  }

  std::vector<float> host;
  cl::Event gate, write;
  cl::Buffer buffer;
  std::thread opener;
};

constexpr auto kGateDelay = std::chrono::milliseconds(300);

TEST(Runtime, ACancelledReadDrainsTheQueueBeforeItThrows) {
  cl::Runtime rt;
  HeldWrite held(rt, kGateDelay);
  rt.set_cancelled([] { return true; });
  float out = 0;
  EXPECT_THROW(rt.read(held.buffer, &out, sizeof out), Cancelled);
  EXPECT_EQ(held.write_status(), CL_COMPLETE);
}

TEST(Runtime, AnAllocationOverTheBudgetDrainsTheQueueBeforeItThrows) {
  cl::Runtime rt(std::make_shared<const cl::Device>(uint64_t{1} << 20));
  HeldWrite held(rt, kGateDelay);
  EXPECT_THROW(rt.alloc(uint64_t{2} << 20), ResourceExhausted);
  EXPECT_EQ(held.write_status(), CL_COMPLETE);
}

TEST(Runtime, NothingDrainsWhileNothingThrows) {
  // The converse, so the two tests above cannot pass by a queue that always runs at once.
  cl::Runtime rt;
  HeldWrite held(rt, kGateDelay);
  EXPECT_NE(held.write_status(), CL_COMPLETE);
  rt.finish();
  EXPECT_EQ(held.write_status(), CL_COMPLETE);
}

}  // namespace
}  // namespace shadow
