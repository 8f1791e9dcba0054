// Short deadlines and cancels against renders and sequences of a 5.5 MiB inline scene, from
// several clients at once (issue 40: such a load ended the server with SIGSEGV, a queued write
// reading a request's freed memory). The server runs in this process, so a crash fails the
// test. Deadlines are drawn across an undisturbed render's own duration, so they land in every
// phase of it: waiting, converting, uploading and checking the scene, rasterizing, streaming.
// SHADOW_STRESS_SECONDS sets the length (default 20 s). Afterwards the server must still serve.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "service/server.hpp"
#include "shadow/v1/shadow.grpc.pb.h"
#include "shadow_client.hpp"
#include "test_scene.hpp"
#include "wire/convert.hpp"

namespace shadow::test {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// A 400 x 400 vertex height field (1.9 MB of positions, 3.8 MB of indices) under a sun.
RenderRequest inline_heavy_scene() {
  RenderRequest r = small_request({Product::kVisibility});
  auto scene = std::make_shared<Scene>(*r.scene);
  constexpr uint32_t n = 400;
  Mesh field;
  for (uint32_t z = 0; z < n; ++z)
    for (uint32_t x = 0; x < n; ++x) {
      const float fx = -8.0f + 16.0f * float(x) / (n - 1), fz = -8.0f + 16.0f * float(z) / (n - 1);
      field.positions.insert(field.positions.end(),
                             {fx, 3.0f + 0.3f * std::sin(fx) * std::cos(fz), fz});
    }
  for (uint32_t z = 0; z + 1 < n; ++z)
    for (uint32_t x = 0; x + 1 < n; ++x) {
      const uint32_t a = z * n + x, b = a + 1, c = a + n, d = c + 1;
      field.indices.insert(field.indices.end(), {a, c, b, b, c, d});
    }
  scene->meshes.push_back(std::move(field));
  scene->instances.push_back({uint32_t(scene->meshes.size() - 1), glm::mat4(1.0f), true, false});
  r.scene = scene;
  return r;
}

int stress_seconds() {
  const char* s = std::getenv("SHADOW_STRESS_SECONDS");
  return s ? std::max(1, std::atoi(s)) : 20;
}

// Reads a Render or RenderSequence stream to its end.
template <class Reader>
grpc::StatusCode drain(Reader& reader) {
  v1::RenderResponse response;
  while (reader->Read(&response)) {
  }
  return reader->Finish().error_code();
}

TEST(Stress, ShortDeadlinesAndCancelsDoNotEndTheServer) {
  service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  service::ShadowServer server(options);
  const v1::RenderRequest request = convert::to_proto(inline_heavy_scene());
  v1::SequenceRequest sequence;
  *sequence.mutable_base() = request;
  for (int i = 0; i < 3; ++i) sequence.add_frames();

  auto stub = v1::ShadowService::NewStub(client::ShadowClient::make_channel(server.address()));
  const auto t0 = Clock::now();
  {
    grpc::ClientContext context;
    auto reader = stub->Render(&context, request);
    ASSERT_EQ(drain(reader), grpc::StatusCode::OK);
  }
  const int render_ms =
      std::max<int>(10, int(std::chrono::duration_cast<milliseconds>(Clock::now() - t0).count()));

  std::mutex mutex;
  std::map<grpc::StatusCode, int> outcomes;
  const auto end = Clock::now() + std::chrono::seconds(stress_seconds());
  const auto client = [&](unsigned seed) {
    std::mt19937 rng(seed);
    // Each client a connection of its own, as separate machines would be.
    grpc::ChannelArguments args;
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    args.SetMaxReceiveMessageSize(-1);
    auto own = v1::ShadowService::NewStub(
        grpc::CreateCustomChannel(server.address(), grpc::InsecureChannelCredentials(), args));
    std::uniform_int_distribution<int> when(1, render_ms * 6 / 5), kind(0, 2);
    while (Clock::now() < end) {
      grpc::ClientContext context;
      const int at = when(rng);
      grpc::StatusCode code;
      switch (kind(rng)) {
        case 0: {  // a deadline
          context.set_deadline(std::chrono::system_clock::now() + milliseconds(at));
          auto reader = own->Render(&context, request);
          code = drain(reader);
          break;
        }
        case 1: {  // the client cancels
          auto reader = own->Render(&context, request);
          std::thread cancel([&] {
            std::this_thread::sleep_for(milliseconds(at));
            context.TryCancel();
          });
          code = drain(reader);
          cancel.join();
          break;
        }
        default: {  // a sequence with a deadline
          context.set_deadline(std::chrono::system_clock::now() + milliseconds(2 * at));
          auto reader = own->RenderSequence(&context, sequence);
          code = drain(reader);
          break;
        }
      }
      std::lock_guard<std::mutex> lock(mutex);
      ++outcomes[code];
    }
  };
  std::vector<std::thread> clients;
  for (unsigned i = 0; i < 4; ++i) clients.emplace_back(client, 1234 + i);
  for (std::thread& c : clients) c.join();

  int calls = 0;
  for (const auto& [code, n] : outcomes) {
    std::printf("status %d: %d calls\n", int(code), n);
    calls += n;
    EXPECT_TRUE(code == grpc::StatusCode::OK || code == grpc::StatusCode::DEADLINE_EXCEEDED ||
                code == grpc::StatusCode::CANCELLED || code == grpc::StatusCode::RESOURCE_EXHAUSTED)
        << "status " << int(code) << " on " << n << " calls";
  }
  std::printf("%d calls in %d s, an undisturbed render %d ms\n", calls, stress_seconds(),
              render_ms);
  EXPECT_GT(outcomes[grpc::StatusCode::DEADLINE_EXCEEDED] + outcomes[grpc::StatusCode::CANCELLED],
            calls / 4);

  // Still serving, and with every workspace back.
  grpc::ClientContext context;
  auto reader = stub->Render(&context, request);
  EXPECT_EQ(drain(reader), grpc::StatusCode::OK);
  EXPECT_EQ(server.engine().load().rendering, 0u);
  EXPECT_EQ(server.engine().load().waiting, 0u);
}

}  // namespace
}  // namespace shadow::test
