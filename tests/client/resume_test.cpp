// The client library resumes across a server restart (issue 40): a shadow-server process is
// killed with SIGKILL in the middle of a call and started again on the same port kRestartDelay
// later, longer than a client that resumed at once would keep trying (issue 40 saw three resumes
// spent in 2.2 s). The call completes: a sequence with every frame once, a render whole, each
// bit-identical to a run without the kill. Loopback only; no timing is asserted but a generous
// bound on the whole call.
#include <signal.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "child_process.hpp"
#include "shadow_client.hpp"
#include "test_scene.hpp"
#include "wire/convert.hpp"

namespace shadow::test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr auto kRestartDelay = 2s;

// A shadow-server listening on `listen` ("127.0.0.1:0": a port the kernel picks); `address`
// gets the address it listens on.
std::unique_ptr<Child> start_server(const std::string& listen, std::string* address = nullptr) {
  auto server = std::make_unique<Child>(
      std::vector<std::string>{SHADOW_SERVER_PATH, "--listen", listen, "--log-format", "none"});
  const std::string line = server->read_line(std::chrono::minutes(2));
  if (line.rfind("listening on ", 0) != 0)
    throw std::runtime_error("shadow-server did not start on " + listen);
  if (address) *address = line.substr(std::strlen("listening on "));
  return server;
}

// Kills `server` with SIGKILL and, on another thread, starts it again on `address` after
// kRestartDelay. The destructor waits for that thread.
class Restart {
 public:
  Restart(std::unique_ptr<Child>& server, const std::string& address) {
    server->stop(SIGKILL);
    killed_ = Clock::now();
    thread_ = std::thread([this, &server, address] {
      std::this_thread::sleep_for(kRestartDelay);
      try {
        server = start_server(address);
        listening_ = Clock::now();
      } catch (const std::exception& e) {
        error_ = e.what();
      }
    });
  }
  ~Restart() { join(); }
  void join() {
    if (thread_.joinable()) thread_.join();
  }
  // Seconds from the kill until the new server listened; throws what the restart threw.
  double outage_s() {
    join();
    if (!error_.empty()) throw std::runtime_error(error_);
    return std::chrono::duration<double>(listening_ - killed_).count();
  }

 private:
  Clock::time_point killed_, listening_;
  std::string error_;
  std::thread thread_;
};

// The textures' bytes and matrices, to compare results bit for bit.
std::vector<std::string> fingerprint(const RenderResult& result) {
  std::vector<std::string> out;
  for (const Texture& t : result.textures) {
    std::string bytes = t.name;
    bytes.append(reinterpret_cast<const char*>(t.data.data()), t.data.size() * sizeof(float));
    bytes.append(reinterpret_cast<const char*>(t.data64.data()), t.data64.size() * sizeof(double));
    bytes.append(reinterpret_cast<const char*>(&t.world_to_ndc), sizeof t.world_to_ndc);
    out.push_back(std::move(bytes));
  }
  return out;
}

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// 24 frames of the test scene from a camera circling it, each with a 1024^2 map (4 MiB): far
// more than the sockets and HTTP/2 windows hold, so after frame 1 the server is still sending.
constexpr int kFrames = 24;
constexpr uint32_t kKillAfterFrame = 1;

v1::SequenceRequest shot() {
  v1::SequenceRequest s;
  *s.mutable_base() = convert::to_proto(small_request({Product::kShadowMap, Product::kVisibility}));
  s.mutable_base()->mutable_shadow_map()->set_size(1024);
  for (int k = 0; k < kFrames; ++k) {
    v1::Camera* camera = s.add_frames()->mutable_camera();
    *camera = s.base().camera();
    const double a = 2 * M_PI * k / kFrames;
    camera->mutable_eye()->set_x(float(12 * std::sin(a)));
    camera->mutable_eye()->set_z(float(12 * std::cos(a)));
  }
  return s;
}

TEST(ResumeAcrossRestart, SequenceDeliversEveryFrameOnce) {
  std::string address;
  std::unique_ptr<Child> server = start_server("127.0.0.1:0", &address);
  client::ShadowClient client(address);
  const v1::SequenceRequest request = shot();
  std::vector<std::vector<std::string>> reference;
  client.render_sequence(request, [&](RenderResult&& r) { reference.push_back(fingerprint(r)); });
  ASSERT_EQ(reference.size(), size_t(kFrames));

  std::unique_ptr<Restart> restart;
  std::vector<int> arrived(kFrames, 0);
  int equal = 0;
  const auto start = Clock::now();
  try {
    client.render_sequence(
        request,
        [&](RenderResult&& r) {
          if (r.frame >= uint32_t(kFrames)) throw std::runtime_error("frame number out of range");
          ++arrived[r.frame];
          equal += fingerprint(r) == reference[r.frame];
          if (r.frame == kKillAfterFrame && !restart)
            restart = std::make_unique<Restart>(server, address);
        },
        60s);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "the sequence failed: " << e.what();
  }
  const double took = seconds_since(start);
  ASSERT_TRUE(restart) << "the server was never killed";
  const double outage = restart->outage_s();
  EXPECT_EQ(arrived, std::vector<int>(kFrames, 1)) << "every frame once";
  EXPECT_EQ(equal, kFrames) << "frames bit-identical to the run without the kill";
  EXPECT_GE(client.stream_restarts(), 1u) << "the kill did not break the stream";
  EXPECT_LT(took, 50.0);
  std::printf(
      "sequence of %d frames: server killed with SIGKILL after frame %u, listening again %.2f s "
      "later; the call completed in %.2f s with %llu resume(s); %d frames equal, each once\n",
      kFrames, kKillAfterFrame, outage, took, (unsigned long long)client.stream_restarts(), equal);
}

TEST(ResumeAcrossRestart, RenderCompletesWhole) {
  std::string address;
  std::unique_ptr<Child> server = start_server("127.0.0.1:0", &address);
  client::ShadowClient client(address);
  // A 4096^2 map (64 MiB): a server killed at its first chunk has not sent the whole reply.
  v1::RenderRequest request =
      convert::to_proto(small_request({Product::kShadowMap, Product::kVisibility}));
  request.mutable_shadow_map()->set_size(4096);
  const std::vector<std::string> reference = fingerprint(client.render(request));

  std::unique_ptr<Restart> restart;
  const client::ShadowClient::Progress kill_at_first_chunk = [&](const convert::ResultAssembler&,
                                                                 size_t texture) {
    if (!restart && texture != convert::ResultAssembler::kNoTexture &&
        texture != client::ShadowClient::kStreamDiscarded)
      restart = std::make_unique<Restart>(server, address);
  };
  const auto start = Clock::now();
  RenderResult result;
  try {
    result = client.render(request, 60s, kill_at_first_chunk);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "the render failed: " << e.what();
  }
  const double took = seconds_since(start);
  ASSERT_TRUE(restart) << "the server was never killed";
  const double outage = restart->outage_s();
  EXPECT_TRUE(fingerprint(result) == reference) << "the render differs from the one without kill";
  EXPECT_GE(client.stream_restarts(), 1u) << "the kill did not break the stream";
  EXPECT_LT(took, 50.0);
  std::printf(
      "4096^2 render: server killed with SIGKILL at the first chunk, listening again %.2f s "
      "later; the call completed in %.2f s with %llu resume(s)\n",
      outage, took, (unsigned long long)client.stream_restarts());
}

}  // namespace
}  // namespace shadow::test
