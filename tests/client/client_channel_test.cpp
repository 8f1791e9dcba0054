// The client library's channel against stand-in servers on loopback (no engine): target lists,
// the x-scene-id key, gRPC's retry policy from client/service_config.json (UNAVAILABLE before a
// reply is retried, on another replica; other codes are not) and render()'s own resume of a
// reply that broke off after it began (with backoff, until the deadline).
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include "channel_target.hpp"
#include "shadow_client.hpp"
#include "wire/scene_id.hpp"

namespace shadow::test {
namespace {

using ::testing::HasSubstr;

TEST(ChannelTarget, OneAddressPassesThroughSeveralBecomeAnIpList) {
  EXPECT_EQ(client::channel_target("127.0.0.1:50051"), "127.0.0.1:50051");
  EXPECT_EQ(client::channel_target("dns:///shadow.example:50051"), "dns:///shadow.example:50051");
  EXPECT_EQ(client::channel_target("localhost:1"), "localhost:1");
  EXPECT_EQ(client::channel_target("127.0.0.1:1,127.0.0.2:2"), "ipv4:127.0.0.1:1,127.0.0.2:2");
  EXPECT_EQ(client::channel_target("[::1]:1,[::1]:2"), "ipv6:[::1]:1,[::1]:2");
  EXPECT_EQ(client::first_host("127.0.0.3:1,127.0.0.2:2"), "127.0.0.3");
  EXPECT_EQ(client::first_host("[::1]:7"), "::1");
}

TEST(ChannelTarget, RefusesWhatGrpcCannotBalance) {
  auto message = [](const std::string& servers) {
    try {
      client::channel_target(servers);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(message("a.example:1,b.example:2"), HasSubstr("'a.example:1': several servers"));
  EXPECT_THAT(message("127.0.0.1:1,[::1]:2"), HasSubstr("mixes IPv4 and IPv6"));
  EXPECT_THAT(message("127.0.0.1:1,"), HasSubstr("an empty address"));
  EXPECT_THAT(message("127.0.0.1:x,127.0.0.1:2"), HasSubstr("expected HOST:PORT"));
  EXPECT_THAT(message("127.0.0.1,127.0.0.2"), HasSubstr("expected HOST:PORT"));
}

TEST(SceneKey, IsTheSha256OfTheDeterministicSerialization) {
  // The empty scene serializes to no bytes: SHA-256 of the empty string.
  EXPECT_EQ(scene_id(v1::Scene()),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  v1::Scene scene;
  scene.add_meshes()->set_positions(std::string(36, '\0'));
  const std::string key = scene_id(scene);
  EXPECT_EQ(key.size(), 64u);
  scene.mutable_meshes(0)->set_indices(std::string(12, '\0'));
  EXPECT_NE(scene_id(scene), key);
}

// A stand-in ShadowService: `behave` answers each Render; it counts calls and keeps what the
// client sent as metadata.
class FakeService final : public v1::ShadowService::Service {
 public:
  using Behaviour = std::function<grpc::Status(int call, grpc::ServerWriter<v1::RenderResponse>*)>;
  explicit FakeService(Behaviour behave) : behave_(std::move(behave)) {
    grpc::ServerBuilder builder;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port_);
    builder.RegisterService(this);
    server_ = builder.BuildAndStart();
    if (!server_ || port_ == 0) throw std::runtime_error("cannot start the fake service");
  }
  ~FakeService() override { server_->Shutdown(); }

  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  int calls() const { return calls_; }
  std::vector<std::string> metadata(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    return key == "x-scene-id" ? scene_ids_ : attempts_;
  }

  grpc::Status Render(grpc::ServerContext* context, const v1::RenderRequest*,
                      grpc::ServerWriter<v1::RenderResponse>* writer) override {
    auto value = [&](const char* key) {
      const auto found = context->client_metadata().find(key);
      return found == context->client_metadata().end()
                 ? std::string("-")
                 : std::string(found->second.data(), found->second.size());
    };
    {
      std::lock_guard<std::mutex> lock(mutex_);
      scene_ids_.push_back(value("x-scene-id"));
      attempts_.push_back(value("grpc-previous-rpc-attempts"));
    }
    return behave_(calls_++, writer);
  }

 private:
  Behaviour behave_;
  int port_ = 0;
  std::unique_ptr<grpc::Server> server_;
  std::atomic<int> calls_{0};
  std::mutex mutex_;
  std::vector<std::string> scene_ids_, attempts_;
};

grpc::Status header_then(grpc::ServerWriter<v1::RenderResponse>* writer, grpc::Status status) {
  v1::RenderResponse header;
  header.mutable_header()->add_passes("fake");
  writer->Write(header);
  return status;
}

v1::RenderRequest request_with_scene() {
  v1::RenderRequest request;
  request.mutable_scene()->add_meshes()->set_positions(std::string(36, '\0'));
  return request;
}

TEST(RetryPolicy, UnavailableBeforeAReplyIsRetried) {
  FakeService fake([](int call, grpc::ServerWriter<v1::RenderResponse>* writer) {
    return call == 0 ? grpc::Status(grpc::StatusCode::UNAVAILABLE, "going away")
                     : header_then(writer, grpc::Status::OK);
  });
  client::ShadowClient client(fake.address());
  const v1::RenderRequest request = request_with_scene();
  EXPECT_EQ(client.render(request).passes, std::vector<std::string>{"fake"});
  EXPECT_EQ(fake.calls(), 2);
  EXPECT_EQ(fake.metadata("grpc-previous-rpc-attempts"), (std::vector<std::string>{"-", "1"}));
  const std::string key = scene_id(request.scene());
  EXPECT_EQ(fake.metadata("x-scene-id"), (std::vector<std::string>{key, key}));
  EXPECT_EQ(client.stream_restarts(), 0u);
}

TEST(RetryPolicy, OtherCodesAreNotRetried) {
  FakeService fake([](int, grpc::ServerWriter<v1::RenderResponse>*) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "camera.width: zero");
  });
  client::ShadowClient client(fake.address());
  try {
    client.render(request_with_scene());
    ADD_FAILURE() << "accepted";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT);
  }
  EXPECT_EQ(fake.calls(), 1);
}

TEST(RetryPolicy, AReplicaThatRefusesIsReplacedByAnother) {
  FakeService down([](int, grpc::ServerWriter<v1::RenderResponse>*) {
    return grpc::Status(grpc::StatusCode::UNAVAILABLE, "draining");
  });
  FakeService up([](int, grpc::ServerWriter<v1::RenderResponse>* writer) {
    return header_then(writer, grpc::Status::OK);
  });
  client::ShadowClient client(down.address() + "," + up.address());
  // round_robin picks among connected replicas only: until both have answered once, every
  // attempt may go to `down` (while `up` still connects), so warm up without asserting.
  for (int i = 0; i < 50 && (up.calls() == 0 || down.calls() == 0); ++i) {
    try {
      client.render(request_with_scene());
    } catch (const client::RpcError&) {
    }
  }
  ASSERT_GT(up.calls(), 0);
  ASSERT_GT(down.calls(), 0);
  const int up_before = up.calls(), down_before = down.calls();
  for (int i = 0; i < 6; ++i) EXPECT_NO_THROW(client.render(request_with_scene())) << i;
  EXPECT_EQ(up.calls() - up_before, 6);
  // round_robin alternates, so each call that `down` refused was retried once, on `up`.
  const std::vector<std::string> attempts = up.metadata("grpc-previous-rpc-attempts");
  const int refused = down.calls() - down_before;
  int retried = 0;
  for (size_t i = size_t(up_before); i < attempts.size(); ++i) retried += attempts[i] == "1";
  EXPECT_EQ(retried, refused);
  EXPECT_GE(refused, 2);
  std::printf("6 renders: %d refused by the draining replica and retried on the other\n", refused);
}

TEST(StreamRestart, AReplyThatBrokeOffIsAskedForAgain) {
  for (const grpc::StatusCode code : {grpc::StatusCode::UNAVAILABLE, grpc::StatusCode::INTERNAL}) {
    FakeService fake([code](int call, grpc::ServerWriter<v1::RenderResponse>* writer) {
      return header_then(writer, call == 0 ? grpc::Status(code, "reset") : grpc::Status::OK);
    });
    client::ShadowClient client(fake.address());
    std::vector<size_t> seen;
    const RenderResult result = client.render(
        request_with_scene(), std::chrono::seconds(30),
        [&](const convert::ResultAssembler&, size_t texture) { seen.push_back(texture); });
    EXPECT_EQ(result.passes, std::vector<std::string>{"fake"});
    EXPECT_EQ(fake.calls(), 2) << code;
    EXPECT_EQ(client.stream_restarts(), 1u);
    // Header, discarded, header again: the caller learns to let go of the first stream.
    EXPECT_EQ(seen, (std::vector<size_t>{convert::ResultAssembler::kNoTexture,
                                         client::ShadowClient::kStreamDiscarded,
                                         convert::ResultAssembler::kNoTexture}));
    // gRPC's retry policy did not retry it (replies had come): these are new calls.
    EXPECT_EQ(fake.metadata("grpc-previous-rpc-attempts"), (std::vector<std::string>{"-", "-"}));
  }
}

TEST(StreamRestart, AResumeThatFindsTheServerNotBackIsResumedAgain) {
  // The first stream breaks after its header; then the server refuses (as a proxy does while its
  // upstream restarts) more often than gRPC's retry policy tries (4 attempts per call), so the
  // client's own resume must go on; then it answers.
  constexpr int kRefusals = 6;
  FakeService fake([](int call, grpc::ServerWriter<v1::RenderResponse>* writer) {
    if (call == 0) return header_then(writer, grpc::Status(grpc::StatusCode::UNAVAILABLE, "died"));
    if (call <= kRefusals) return grpc::Status(grpc::StatusCode::UNAVAILABLE, "no upstream");
    return header_then(writer, grpc::Status::OK);
  });
  client::ShadowClient client(fake.address());
  EXPECT_EQ(client.render(request_with_scene(), std::chrono::seconds(30)).passes,
            std::vector<std::string>{"fake"});
  EXPECT_EQ(fake.calls(), 2 + kRefusals);
  EXPECT_GE(client.stream_restarts(), 2u);
}

TEST(StreamRestart, GoesOnUntilTheDeadlineAndNotForOtherCodes) {
  FakeService broken([](int, grpc::ServerWriter<v1::RenderResponse>* writer) {
    return header_then(writer, grpc::Status(grpc::StatusCode::UNAVAILABLE, "reset"));
  });
  client::ShadowClient client(broken.address());
  const auto start = std::chrono::steady_clock::now();
  try {
    client.render(request_with_scene(), std::chrono::seconds(3));
    ADD_FAILURE() << "accepted";
  } catch (const client::RpcError& e) {
    // The stream's own error, unless an attempt ran into the deadline.
    EXPECT_TRUE(e.code() == grpc::StatusCode::UNAVAILABLE ||
                e.code() == grpc::StatusCode::DEADLINE_EXCEEDED)
        << e.code();
  }
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // The pauses before the first four resumes are at most 0.1 + 0.2 + 0.4 + 0.8 s: all fit in 3 s.
  EXPECT_GE(broken.calls(), 5);
  EXPECT_LT(took, 10.0);
  std::printf("a stream that always breaks: %d calls in %.2f s of a 3 s deadline\n", broken.calls(),
              took);

  FakeService late_error([](int, grpc::ServerWriter<v1::RenderResponse>* writer) {
    return header_then(writer, grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "full"));
  });
  client::ShadowClient other(late_error.address());
  EXPECT_THROW(other.render(request_with_scene()), client::RpcError);
  EXPECT_EQ(late_error.calls(), 1);
}

}  // namespace
}  // namespace shadow::test
