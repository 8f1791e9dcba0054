// The shadow-server executable itself: it starts on a free port, announces "listening on ADDR",
// answers health checks, reflection and a render, and exits cleanly on SIGTERM.
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include "child_process.hpp"
#include "shadow_client.hpp"
#include "test_scene.hpp"

namespace shadow::test {
namespace {

// Asks server reflection (grpc.reflection.v1alpha, bidi stream) to list services, with a
// hand-encoded request: Debian ships no reflection.proto for C++ clients. Returns the raw reply.
std::string list_services(const std::shared_ptr<grpc::Channel>& channel) {
  grpc::GenericStub stub(channel);
  grpc::CompletionQueue cq;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  auto call = stub.PrepareCall(
      &context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &cq);
  auto step = [&](auto start) {
    void* tag = nullptr;
    bool ok = false;
    start(reinterpret_cast<void*>(1));
    return cq.Next(&tag, &ok) && ok;
  };
  std::string reply;
  // ServerReflectionRequest { list_services = "" }: field 7, length-delimited, empty.
  const std::string request("\x3a\x00", 2);
  grpc::Slice slice(request);
  grpc::ByteBuffer out(&slice, 1), in;
  if (step([&](void* t) { call->StartCall(t); }) && step([&](void* t) { call->Write(out, t); }) &&
      step([&](void* t) { call->WritesDone(t); }) && step([&](void* t) { call->Read(&in, t); })) {
    std::vector<grpc::Slice> slices;
    in.Dump(&slices);
    for (const grpc::Slice& s : slices)
      reply.append(reinterpret_cast<const char*>(s.begin()), s.size());
  }
  grpc::Status status;
  step([&](void* t) { call->Finish(&status, t); });
  cq.Shutdown();
  void* tag;
  bool ok;
  while (cq.Next(&tag, &ok)) {
  }
  return reply;
}

TEST(ServerBinary, ServesHealthReflectionAndARenderThenStopsOnSigterm) {
  Child server({SHADOW_SERVER_PATH, "--listen", "127.0.0.1:0"});
  // Cold kernel builds can take a while on a busy machine; this only guards against a hang.
  const std::string line = server.read_line(std::chrono::minutes(5));
  const std::string prefix = "listening on ";
  ASSERT_EQ(line.rfind(prefix, 0), 0u) << "first line: '" << line << "'";
  const std::string address = line.substr(prefix.size());
  ASSERT_NE(address.find("127.0.0.1:"), std::string::npos);
  ASSERT_EQ(address.find(":0"), std::string::npos) << "the chosen port is printed";

  {
    // Closed before SIGTERM: an open connection would hold shutdown for its grace period.
    auto channel = client::ShadowClient::make_channel(address);
    client::ShadowClient client(channel);
    EXPECT_TRUE(client.healthy());
    const RenderResult r = client.render(tiny_proto_request());
    EXPECT_EQ(r.textures.size(), 3u);

    const std::string services = list_services(channel);
    EXPECT_NE(services.find("shadow.v1.ShadowService"), std::string::npos);
    EXPECT_NE(services.find("grpc.health.v1.Health"), std::string::npos);
  }

  const int status = server.stop(SIGTERM);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

// A calibration table that is missing or malformed stops the server before it listens, with a
// message naming the file, the line and what is wrong.
TEST(ServerBinary, RefusesABadCalibrationTableAtStartUp) {
  const std::string bad = ::testing::TempDir() + "bad_calibration.csv";
  std::ofstream(bad) << "technique,footprint_px_max,misclassified_per_boundary_pixel,pixels\n"
                        "uniform,1,-2,3\n";
  const std::pair<std::string, std::string> cases[] = {
      {bad, bad + ":2: misclassified_per_boundary_pixel must be a number >= 0"},
      {"/nonexistent/calibration.csv", "/nonexistent/calibration.csv: cannot be read"}};
  for (const auto& [path, message] : cases) {
    const std::string err = ::testing::TempDir() + "calibration_stderr.txt";
    Child server({SHADOW_SERVER_PATH, "--listen", "127.0.0.1:0", "--calibration", path}, err);
    EXPECT_EQ(server.read_line(std::chrono::minutes(1)), "") << "it must not listen";
    const int status = server.stop(SIGKILL);
    ASSERT_TRUE(WIFEXITED(status)) << path;
    EXPECT_EQ(WEXITSTATUS(status), 2) << path;
    std::stringstream text;
    text << std::ifstream(err).rdbuf();
    EXPECT_NE(text.str().find("--calibration " + message), std::string::npos) << text.str();
  }
}

}  // namespace
}  // namespace shadow::test
