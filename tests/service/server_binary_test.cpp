// The shadow-server executable itself: it starts on a free port, announces "listening on ADDR",
// answers health checks, reflection and a render, and exits cleanly on SIGTERM.
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>

#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include "shadow_client.hpp"
#include "test_scene.hpp"

extern char** environ;

namespace shadow::test {
namespace {

// A child process with its stdout on a pipe; killed on destruction if still running.
class Child {
 public:
  explicit Child(std::vector<std::string> args) {
    int fds[2];
    if (pipe(fds) != 0) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int err = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    out_ = fds[0];
    if (err != 0) throw std::runtime_error("cannot start " + args[0]);
  }
  ~Child() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    close(out_);
  }

  // The next line of stdout, or "" at EOF or after `timeout` (a guard against hangs only).
  std::string read_line(std::chrono::milliseconds timeout) {
    std::string line;
    const auto end = std::chrono::steady_clock::now() + timeout;
    char c;
    while (std::chrono::steady_clock::now() < end) {
      pollfd p{out_, POLLIN, 0};
      if (poll(&p, 1, 100) <= 0) continue;
      if (read(out_, &c, 1) != 1) break;
      if (c == '\n') return line;
      line += c;
    }
    return "";
  }

  // Sends `signal` and returns the wait status.
  int stop(int signal) {
    kill(pid_, signal);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return status;
  }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
};

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

}  // namespace
}  // namespace shadow::test
