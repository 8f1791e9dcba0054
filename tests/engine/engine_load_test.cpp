// The engine under loads that used to end the process or hold everyone up (issue 40): the idle
// trim with no budget left, requests that fit one at a time but not together, a sequence read
// slower than it renders beside a bystander, and a request that cannot fit beside what replies
// hold. Each engine here is small and its own: budgets and queues are what is tested.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <future>
#include <thread>
#include <vector>

#include "engine/cost.hpp"
#include "engine/plan.hpp"
#include "occluder_scene.hpp"

namespace shadow {
namespace {

using namespace std::chrono_literals;
using testing::occluder_request;

// The device buffers the engine waits for before it renders `r`.
uint64_t needed_bytes(const RenderRequest& r) {
  return estimate_cost(r, make_plan(r)).device_bytes;
}

RenderRequest heavy_request() {
  RenderRequest r = occluder_request();
  r.shadow_map.size = 4096;  // a 64 MiB depth map, well over everything else the request holds
  r.products = {Product::kVisibility};
  return r;
}

TEST(EngineLoad, TheIdleTrimWithNoBudgetLeftDoesNotEndTheProcess) {
  // Before issue 40 the trimmer's fresh workspace threw ResourceExhausted on its own thread,
  // and std::terminate ended the process (this test binary with it).
  EngineOptions o;
  o.memory_budget = uint64_t{256} << 20;
  o.idle_memory_bytes = 0;
  o.idle_trim_delay_ms = 50;
  Engine engine(o);
  engine.render(occluder_request());
  cl::Reservation rest = engine.reserve(
      engine.memory_budget_bytes() - engine.device_bytes_in_use() - 8, "the test's hold");
  std::this_thread::sleep_for(400ms);  // past the trim delay, several times over
  rest = {};
  const RenderResult after = engine.render(occluder_request());
  EXPECT_FALSE(after.textures.empty());
}

TEST(EngineLoad, RequestsThatFitOneAtATimeRunOneAfterAnother) {
  const RenderRequest r = heavy_request();
  EngineOptions o;
  // Room for one such request and its scratch, not for two.
  o.memory_budget = needed_bytes(r) * 3 / 2 + (uint64_t{32} << 20);
  o.max_concurrent = 2;
  Engine engine(o);
  std::vector<std::future<RenderResult>> runs;
  for (int i = 0; i < 2; ++i)
    runs.push_back(std::async(std::launch::async, [&] { return engine.render(r); }));
  std::vector<RenderResult> results;
  for (auto& run : runs) ASSERT_NO_THROW(results.push_back(run.get()));
  // The same bits (NaN where the camera sees nothing), whichever ran first.
  const std::vector<float>&a = results[0].textures.at(0).data, &b = results[1].textures.at(0).data;
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
}

TEST(EngineLoad, ARequestThatCannotFitBesideHeldRepliesIsRefusedNotHeld) {
  const RenderRequest r = heavy_request();
  EngineOptions o;
  o.memory_budget = needed_bytes(r) * 3 / 2 + (uint64_t{32} << 20);
  Engine engine(o);
  // Replies being streamed hold most of the budget and nothing renders to give it back.
  cl::Reservation replies = engine.reserve(needed_bytes(r), "replies");
  try {
    engine.render(r);
    FAIL() << "rendered beside the held replies";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "memory_budget");
  }
  replies = {};
  EXPECT_NO_THROW(engine.render(r));
}

TEST(EngineLoad, ASlowSequenceReaderHoldsNoWorkspaceWhileOthersWait) {
  EngineOptions o;
  o.max_concurrent = 1;  // the one workspace the reader would hold
  Engine engine(o);
  SequenceRequest s;
  s.base = occluder_request();
  s.frames.resize(12);
  std::atomic<int> frames_read{0};
  std::promise<void> first_frame;
  std::future<void> sequence = std::async(std::launch::async, [&] {
    engine.render_sequence(s, [&](RenderResult&&) {
      if (frames_read++ == 0) first_frame.set_value();
      std::this_thread::sleep_for(250ms);  // the client takes a frame every quarter second
    });
  });
  first_frame.get_future().wait();
  const RenderResult bystander = engine.render(occluder_request());
  const int read_when_served = frames_read.load();
  sequence.get();
  EXPECT_EQ(frames_read.load(), 12);
  // Before issue 40 the bystander waited for all 12 frames (3 s); now for one frame's handover.
  EXPECT_LT(read_when_served, 6) << "bystander waited " << bystander.queue_ms << " ms";
}

}  // namespace
}  // namespace shadow
