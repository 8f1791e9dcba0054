// Several requests at once through the real server: a full queue, deadlines and cancellation
// that stop the work, the device-memory budget, idle trimming, and a port that is taken.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <future>
#include <thread>

#include <gtest/gtest.h>

#include "service/server.hpp"
#include "shadow_client.hpp"
#include "test_scene.hpp"
#include "wire/convert.hpp"

namespace shadow::test {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::unique_ptr<service::ShadowServer> start(
    EngineOptions engine, std::chrono::milliseconds stall_timeout = std::chrono::seconds(30)) {
  service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  options.engine = engine;
  options.stall_timeout = stall_timeout;
  return std::make_unique<service::ShadowServer>(options);
}

// One workspace, so a heavy request holds up the next; no cost limit, so the heavy request runs
// whatever the cost model's margin.
EngineOptions one_workspace() {
  EngineOptions engine;
  engine.max_concurrent = 1;
  engine.max_request_cost_ms = 0;
  return engine;
}

// An 8K camera with 64 + 64-tap PCSS: 6.9 s on 2 cores here, 6.0 s of it in the one PCSS pass
// (0.6 s in), which runs as 64 launches of 8192 work-items, ~95 ms each.
RenderRequest heavy_request() {
  RenderRequest r = small_request({Product::kVisibility});
  r.camera.width = 7680;
  r.camera.height = 4320;
  r.lights[0].size = 2.0f;
  r.filter.kind = FilterKind::kPcss;
  r.filter.pcss.blocker_samples = 64;
  r.filter.pcss.filter_samples = 64;
  return r;
}

grpc::StatusCode code_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const client::RpcError& e) {
    return e.code();
  }
  return grpc::StatusCode::OK;
}

// Time from a heavy request's end (deadline or cancel, in its PCSS pass) to a small request's
// reply on the only workspace: the heavy one stops within a slice or two instead of running
// ~6 s to its end. Measured 0.1-0.3 s.
double small_render_seconds(client::ShadowClient& client) {
  const auto t0 = Clock::now();
  EXPECT_EQ(client.render(small_request()).textures.size(), 3u);
  return seconds_since(t0);
}

TEST(Concurrency, DeadlineStopsTheRenderAndFreesTheWorkspace) {
  auto server = start(one_workspace());
  client::ShadowClient client(server->address());

  EXPECT_EQ(code_of([&] { client.render(heavy_request(), std::chrono::milliseconds(1000)); }),
            grpc::StatusCode::DEADLINE_EXCEEDED);
  const double after = small_render_seconds(client);
  std::printf("after the deadline the next small render took %.3f s\n", after);
  EXPECT_LT(after, 1.0);
}

TEST(Concurrency, ClientCancelStopsTheRender) {
  auto server = start(one_workspace());
  auto stub = v1::ShadowService::NewStub(client::ShadowClient::make_channel(server->address()));

  grpc::ClientContext context;
  const v1::RenderRequest request = convert::to_proto(heavy_request());
  auto reader = stub->Render(&context, request);
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));  // into the PCSS pass
  context.TryCancel();
  v1::RenderResponse response;
  while (reader->Read(&response)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);

  client::ShadowClient client(server->address());
  const double after = small_render_seconds(client);
  std::printf("after the cancel the next small render took %.3f s\n", after);
  EXPECT_LT(after, 1.0);
}

TEST(Concurrency, FullQueueIsResourceExhaustedAndSaysSo) {
  EngineOptions engine = one_workspace();
  engine.max_queue = 0;
  auto server = start(engine);
  client::ShadowClient client(server->address());

  auto heavy = std::async(std::launch::async, [&] {
    return code_of([&] { client.render(heavy_request(), std::chrono::milliseconds(1500)); });
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(400));  // the heavy one is rendering
  // Another client on a connection of its own: the server caps each connection's open calls at
  // what can render or wait, so a second call on the first connection would wait at the client.
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  client::ShadowClient other(
      grpc::CreateCustomChannel(server->address(), grpc::InsecureChannelCredentials(), args));
  try {
    other.render(small_request());
    ADD_FAILURE() << "a request past a full queue was served";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(std::string(e.what()).find("queue is full"), std::string::npos) << e.what();
  }
  EXPECT_EQ(heavy.get(), grpc::StatusCode::DEADLINE_EXCEEDED);
  // The client hears of its deadline at once; the server frees the workspace a slice later.
  const auto t0 = Clock::now();
  grpc::StatusCode code;
  while ((code = code_of([&] { client.render(small_request()); })) ==
             grpc::StatusCode::RESOURCE_EXHAUSTED &&
         seconds_since(t0) < 1.0)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(code, grpc::StatusCode::OK);
}

TEST(Concurrency, TwoRequestsRenderAtOnceWithTheSameResults) {
  EngineOptions engine;
  engine.max_concurrent = 2;
  auto server = start(engine);
  client::ShadowClient client(server->address());
  const RenderResult alone = client.render(small_request());
  std::vector<std::future<RenderResult>> both;
  for (int i = 0; i < 4; ++i)
    both.push_back(std::async(std::launch::async, [&] { return client.render(small_request()); }));
  for (auto& f : both) {
    const RenderResult r = f.get();
    ASSERT_EQ(r.textures.size(), alone.textures.size());
    for (size_t t = 0; t < r.textures.size(); ++t)  // bitwise: NaN marks empty pixels
      EXPECT_EQ(std::memcmp(r.textures[t].data.data(), alone.textures[t].data.data(),
                            alone.textures[t].byte_size()),
                0)
          << r.textures[t].name;
  }
}

TEST(Concurrency, OverTheMemoryBudgetIsResourceExhaustedNamingIt) {
  EngineOptions engine;
  engine.memory_budget = uint64_t{48} << 20;
  auto server = start(engine);
  client::ShadowClient client(server->address());
  RenderRequest big = small_request({Product::kShadowMap});
  big.shadow_map.size = 4096;  // a 64 MiB depth buffer alone
  try {
    client.render(big);
    ADD_FAILURE() << "a request over the memory budget was served";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(std::string(e.what()).find("memory_budget"), std::string::npos) << e.what();
    // Refused at admission, from the plan, before it waited or enqueued anything.
    EXPECT_NE(std::string(e.what()).find("whole memory budget"), std::string::npos) << e.what();
  }
  EXPECT_EQ(client.render(small_request()).textures.size(), 3u);
}

RenderRequest big_request() {
  RenderRequest big = small_request({Product::kShadowMap, Product::kShadowMapSat});
  big.shadow_map.size = 2048;  // 16 MiB map + 32 MiB SAT on the device
  return big;
}

// An engine that trims above 16 MiB (less than big_request holds) once idle for `delay_ms`.
EngineOptions trimming_after(uint32_t delay_ms) {
  EngineOptions engine;
  engine.idle_memory_bytes = uint64_t{16} << 20;
  engine.idle_trim_delay_ms = delay_ms;
  return engine;
}

TEST(Concurrency, AnIdleServerGivesLargeBuffersBackAfterTheDelay) {
  const EngineOptions engine = trimming_after(200);
  auto server = start(engine);
  client::ShadowClient client(server->address());
  client.render(big_request());
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (server->engine().device_bytes_in_use() > engine.idle_memory_bytes &&
         std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_LE(server->engine().device_bytes_in_use(), engine.idle_memory_bytes);
}

// Within the delay the buffers stay for the client's next request (trimmed between requests,
// each big one faulted its buffers in again).
TEST(Concurrency, LargeBuffersStayWhileRequestsKeepComing) {
  const EngineOptions engine = trimming_after(60000);
  auto server = start(engine);
  client::ShadowClient client(server->address());
  for (int i = 0; i < 2; ++i) {
    client.render(big_request());
    EXPECT_GT(server->engine().device_bytes_in_use(), engine.idle_memory_bytes) << i;
  }
}

// With no delay they go as soon as the last request ends.
TEST(Concurrency, WithoutADelayLargeBuffersGoWhenTheLastRequestEnds) {
  const EngineOptions engine = trimming_after(0);
  auto server = start(engine);
  client::ShadowClient client(server->address());
  client.render(big_request());
  EXPECT_LE(server->engine().device_bytes_in_use(), engine.idle_memory_bytes);
}

// Four clients read only the header of a 192 MiB reply and stop. The watchdog cancels them after
// the stall timeout, and their replies' memory goes back to the budget.
TEST(Concurrency, ReadersThatStopAreCancelledAndTheirRepliesFreed) {
  EngineOptions engine;
  engine.idle_trim_delay_ms = 100;  // the workspaces' buffers go well before the check below
  auto server = start(engine, std::chrono::milliseconds(500));
  const uint64_t idle = server->engine().device_bytes_in_use();
  RenderRequest big = small_request({Product::kShadowMap, Product::kShadowMapSat});
  big.shadow_map.size = 4096;  // 64 MiB map + 128 MiB SAT
  const v1::RenderRequest proto = convert::to_proto(big);
  auto stub = v1::ShadowService::NewStub(client::ShadowClient::make_channel(server->address()));
  std::vector<std::future<grpc::StatusCode>> readers;
  std::vector<std::promise<void>> headers(4);
  for (int i = 0; i < 4; ++i)
    readers.push_back(std::async(std::launch::async, [&, i] {
      grpc::ClientContext context;
      auto reader = stub->Render(&context, proto);
      v1::RenderResponse header;
      EXPECT_TRUE(reader->Read(&header));  // the render is done, its reply reserved
      headers[i].set_value();
      std::this_thread::sleep_for(std::chrono::seconds(4));  // reads nothing more
      context.TryCancel();
      return reader->Finish().error_code();
    }));
  for (auto& h : headers) h.get_future().wait();
  // Well before the readers give up, the server has dropped them and freed their replies.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  EXPECT_LE(server->engine().device_bytes_in_use(),
            std::max(idle, server->engine().options().idle_memory_bytes));
  for (auto& r : readers) EXPECT_EQ(r.get(), grpc::StatusCode::CANCELLED);
}

// The heavy request is estimated at ~7.8 s (it takes 3-7 s here): under the default limit, over
// a server's limit of 2 s.
TEST(Concurrency, OverTheCostLimitIsRefusedWithTheEstimate) {
  EngineOptions engine;
  engine.max_request_cost_ms = 2000;
  auto server = start(engine);
  client::ShadowClient client(server->address());
  try {
    client.render(heavy_request());
    ADD_FAILURE() << "an 8K PCSS-64/64 request was admitted under a 2 s limit";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(std::string(e.what()).find("request cost: the request is estimated at"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("visibility.pcss"), std::string::npos) << e.what();
  }
}

// 8192 triangles that each cover the whole 2048^2 map are few and cheap to upload, but each
// lands in all 1024 tiles: ~10 s of rasterizing here (4096 took 5.0 s). Binning counts the
// overlaps, and the request is refused before the raster pass runs.
TEST(Concurrency, TooManyTriangleTileOverlapsAreRefusedAfterBinning) {
  auto server = start(EngineOptions{});
  client::ShadowClient client(server->address());
  RenderRequest r = small_request({Product::kShadowMap});
  r.shadow_map.size = 2048;
  auto scene = std::make_shared<Scene>(*r.scene);
  Mesh m;
  for (uint32_t i = 0; i < 8192; ++i) {
    const float h = 0.5f + 0.00025f * float(i);
    m.positions.insert(m.positions.end(), {-40, h, -40, 40, h, -40, 0, h, 40});
    m.indices.insert(m.indices.end(), {3 * i, 3 * i + 2, 3 * i + 1});
  }
  scene->meshes.push_back(m);
  Instance inst;
  inst.mesh = 2;
  scene->instances.push_back(inst);
  r.scene = scene;
  const auto t0 = Clock::now();
  try {
    client.render(r);
    ADD_FAILURE() << "served";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(std::string(e.what()).find("triangle-tile overlaps"), std::string::npos) << e.what();
  }
  EXPECT_LT(seconds_since(t0), 3.0);
  EXPECT_EQ(client.render(small_request()).textures.size(), 3u);
}

// A request's own message counts against the budget while it waits and renders.
TEST(Concurrency, ARequestLargerThanTheBudgetIsRefusedBeforeItWaits) {
  EngineOptions engine;
  engine.memory_budget = uint64_t{24} << 20;
  auto server = start(engine);
  RenderRequest r = small_request();
  auto scene = std::make_shared<Scene>(*r.scene);
  scene->meshes[0].positions.resize(3 * 1'000'000, 0.0f);  // 12 MB of vertices on the wire
  r.scene = scene;
  try {
    client::ShadowClient(server->address()).render(r);
    ADD_FAILURE() << "served";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    // The refusal names the need and the budget.
    EXPECT_NE(std::string(e.what()).find("a request needs 22.9 MiB"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("24 MiB (25165824 bytes) memory budget"),
              std::string::npos)
        << e.what();
  }
}

// Issue 51's Estimate call: admission's figures without rendering, the refusal a request or a
// sequence would meet, and INVALID_ARGUMENT for what Render would refuse as invalid.
TEST(Concurrency, EstimatePricesWorkWithoutRenderingIt) {
  EngineOptions engine;
  engine.max_request_cost_ms = 2000;
  engine.max_sequence_cost_ms = 60e3;
  auto server = start(engine);
  client::ShadowClient client(server->address());
  v1::EstimateRequest small;
  *small.mutable_render() = convert::to_proto(small_request());
  const v1::Price ok = client.estimate(small);
  EXPECT_TRUE(ok.admitted()) << ok.refusal();
  EXPECT_GT(ok.device_ms(), 0);
  EXPECT_GT(ok.device_bytes(), 0u);
  EXPECT_GT(ok.reply_bytes(), 0u);
  EXPECT_EQ(ok.max_request_cost_ms(), 2000);
  EXPECT_EQ(ok.memory_budget(), server->engine().memory_budget_bytes());
  v1::EstimateRequest heavy;
  *heavy.mutable_render() = convert::to_proto(heavy_request());
  const v1::Price over = client.estimate(heavy);
  EXPECT_FALSE(over.admitted());
  EXPECT_EQ(over.refused_field(), "request cost");
  EXPECT_NE(over.refusal().find("over the server's limit of 2 s"), std::string::npos)
      << over.refusal();
  // 1000 frames of the small request: priced as a whole against the sequence limit.
  v1::EstimateRequest sequence;
  *sequence.mutable_sequence()->mutable_base() = convert::to_proto(small_request());
  for (int i = 0; i < 1000; ++i) sequence.mutable_sequence()->add_frames();
  const v1::Price frames = client.estimate(sequence);
  EXPECT_EQ(frames.frames(), 1000u);
  EXPECT_NEAR(frames.device_ms(), 1000 * ok.device_ms(), 1e-6 * frames.device_ms());
  EXPECT_EQ(server->engine().load().rendering, 0u);
  v1::EstimateRequest invalid = small;
  invalid.mutable_render()->mutable_camera()->set_width(0);
  try {
    client.estimate(invalid);
    ADD_FAILURE() << "priced an invalid request";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT);
  }
  try {
    client.estimate(v1::EstimateRequest());
    ADD_FAILURE() << "priced nothing";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(std::string(e.what()).find("work"), std::string::npos) << e.what();
  }
}

TEST(Concurrency, ASecondServerOnATakenPortDoesNotStart) {
  auto first = start(EngineOptions{});
  service::ServerOptions options;
  options.listen = first->address();
  EXPECT_THROW(service::ShadowServer second(options), std::runtime_error);
  EXPECT_TRUE(client::ShadowClient(first->address()).healthy());
}

}  // namespace
}  // namespace shadow::test
