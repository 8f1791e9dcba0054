// The shadow-server executable itself: it starts on a free port, announces "listening on ADDR",
// answers health checks, reflection and a render, and exits cleanly on SIGTERM; option values
// that cannot work stop it at start-up with exit code 2, naming the flag.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include "child_process.hpp"
#include "engine/cl/device_choice.hpp"
#include "shadow_client.hpp"
#include "test_scene.hpp"
#include "wire/convert.hpp"

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

// Starts shadow-server with `args` (on 127.0.0.1:0 unless they name --listen) and expects it to
// refuse them before it listens: exit code 2 and `message` on stderr. A server that takes them
// (as before these checks) builds its engine and listens: the test fails then, after a while.
void expect_refused(const std::vector<std::string>& args, const std::string& message) {
  std::vector<std::string> argv = {SHADOW_SERVER_PATH};
  if (std::find(args.begin(), args.end(), "--listen") == args.end())
    argv.insert(argv.end(), {"--listen", "127.0.0.1:0"});
  argv.insert(argv.end(), args.begin(), args.end());
  std::string command;
  for (const std::string& a : args) command += " " + a;
  // Per process: ctest -j runs this file's tests side by side, each in a process of its own.
  const std::string err =
      ::testing::TempDir() + "refused_stderr_" + std::to_string(getpid()) + ".txt";
  Child server(argv, err);
  EXPECT_EQ(server.read_line(std::chrono::minutes(5)), "") << command << ": it must not listen";
  const int status = server.stop(SIGKILL);
  ASSERT_TRUE(WIFEXITED(status)) << command;
  EXPECT_EQ(WEXITSTATUS(status), 2) << command;
  std::stringstream text;
  text << std::ifstream(err).rdbuf();
  EXPECT_NE(text.str().find(message), std::string::npos) << command << ": " << text.str();
}

// Values that started a broken server (every long reply CANCELLED, every request refused, a
// random port, a budget of 2^64 - 1) or that CLI11 refused with codes of its own.
TEST(ServerBinary, RefusesBadOptionValuesAtStartUpNamingTheFlag) {
  const std::string seconds = "--stall-timeout: must be a finite number of seconds in (0, 86400]";
  for (const char* value : {"1e16", "1e300", "nan", "inf", "0", "-1"})
    expect_refused({"--stall-timeout", value}, seconds + ": got " + value);
  for (const char* flag : {"--max-request-cost", "--overtake-max-cost"})
    for (const char* value : {"nan", "inf", "-1"})
      expect_refused(
          {flag, value},
          std::string(flag) + ": must be a finite number of milliseconds >= 0: got " + value);
  for (const char* flag : {"--max-connection-age", "--max-connection-age-grace"})
    for (const char* value : {"nan", "inf", "1e300"})
      expect_refused({flag, value},
                     std::string(flag) + ": must be a finite number of seconds in [0, 2147483]");
  for (const char* value :
       {"127.0.0.1:99999", "127.0.0.1:-1", "127.0.0.1", ":50051", "127.0.0.1:port", "::1:0"})
    expect_refused({"--listen", value}, "--listen: must be HOST:PORT with a port in 0..65535");
  for (const char* flag : {"--memory-budget", "--max-queue", "--scene-cache-bytes",
                           "--tenant-scene-cache-bytes", "--device-scene-bytes",
                           "--idle-trim-delay", "--overtake-window", "--tenant-max-concurrent"})
    expect_refused({flag, "-1"}, std::string(flag) + ": must be a whole number >= 0: got -1");
  for (const char* flag : {"--max-output-bytes", "--max-request-bytes"})
    for (const char* value : {"-1", "0"})
      expect_refused({flag, value},
                     std::string(flag) + ": must be a whole number >= 1: got " + value);
  expect_refused({"--memory-budget", "18446744073709551616"},
                 "--memory-budget: must be below 2^64");
  // CLI11's own refusals exit 2 as well.
  expect_refused({"--max-queue", "many"}, "--max-queue");
  expect_refused({"--max-concurrent", "0"}, "--max-concurrent");
  expect_refused({"--no-such-flag"}, "--no-such-flag");
}

// The address forms that must keep working pass the --listen check: each run stops at the next,
// bad, flag instead (without building an engine).
TEST(ServerBinary, TakesIpv6AndNamedHostsToListenOn) {
  for (const char* listen : {"[::1]:0", "[::]:50051", "0.0.0.0:65535", "localhost:0"})
    expect_refused({"--listen", listen, "--memory-budget", "-1"}, "--memory-budget");
}

// A certificate or key that does not load was reported as a port that could not be bound.
TEST(ServerBinary, RefusesBadCertificatesAndKeysAtStartUpNamingTheFlag) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("shadow-bad-certs-" + std::to_string(getpid()));
  const std::string command = std::string("bash ") + SHADOW_MAKE_CERTS + " " + dir.string();
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const auto file = [&](const std::string& name) { return (dir / name).string(); };
  std::ofstream(file("garbage.pem")) << "not a certificate\n";
  std::ofstream(file("broken.pem")) << "-----BEGIN CERTIFICATE-----\nbm90IGEgY2VydGlmaWNhdGU=\n"
                                       "-----END CERTIFICATE-----\n";
  std::ofstream(file("tokens")) << "secret alice\n";
  const std::string cert = file("server.pem"), key = file("server.key");

  expect_refused({"--tls-cert", file("garbage.pem"), "--tls-key", key},
                 "--tls-cert: " + file("garbage.pem") + " holds no PEM certificate");
  expect_refused({"--tls-cert", file("broken.pem"), "--tls-key", key},
                 "--tls-cert: certificate 1 of " + file("broken.pem") + " does not parse");
  expect_refused({"--tls-cert", cert, "--tls-key", file("garbage.pem")},
                 "--tls-key: " + file("garbage.pem") + " holds no unencrypted PEM private key");
  expect_refused({"--tls-cert", cert, "--tls-key", file("client.key")},
                 "--tls-key: " + file("client.key") +
                     " is not the key of the certificate in "
                     "--tls-cert " +
                     cert);
  expect_refused({"--tls-cert", cert, "--tls-key", key, "--tls-client-ca", file("garbage.pem")},
                 "--tls-client-ca: " + file("garbage.pem") + " holds no PEM certificate");
  expect_refused({"--tls-cert", file("missing.pem"), "--tls-key", key},
                 "--tls-cert: cannot read " + file("missing.pem"));
  expect_refused({"--auth-tokens", file("tokens")}, "--auth-tokens needs TLS");
  fs::remove_all(dir);
}

// Sets an environment variable for the servers a test starts (they inherit it), and restores it.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) saved_ = old;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (saved_.empty())
      unsetenv(name_);
    else
      setenv(name_, saved_.c_str(), 1);
  }

 private:
  const char* name_;
  std::string saved_;
};

// `shadow-server --list-devices`: its stdout and its exit code.
std::pair<std::string, int> list_devices() {
  Child lister({SHADOW_SERVER_PATH, "--list-devices"});
  std::string out;
  for (std::string line; !(line = lister.read_line(std::chrono::minutes(1))).empty();)
    out += line + "\n";
  const int status = lister.stop(SIGKILL);
  return {out, WIFEXITED(status) ? WEXITSTATUS(status) : -1};
}

bool has_pocl(const std::string& list) {
  return list.find("Portable Computing Language") != std::string::npos;
}

// The lines of a file.
std::vector<std::string> lines_of(const std::string& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  return text;
}

// A first start (PoCL's cache empty) says what it is doing while it builds the kernels, and
// nothing else: not the OpenCL compiler's bare "N warnings generated." per program. A second
// server on the same port then fails in one line of its own, without gRPC's raw error line.
TEST(ServerBinary, StartUpSaysWhatItDoesAndNothingElse) {
  namespace fs = std::filesystem;
  const fs::path cache =
      fs::temp_directory_path() / ("shadow-cold-pocl-" + std::to_string(getpid()));
  fs::remove_all(cache);
  fs::create_directories(cache);
  ScopedEnv cold_cache("POCL_CACHE_DIR", cache.string());
  ScopedEnv quiet("POCL_DEBUG", "");  // restored after; unset meanwhile: it shows PoCL's output
  unsetenv("POCL_DEBUG");
  const std::string first_err = ::testing::TempDir() + "cold_start_stderr.txt";
  Child first({SHADOW_SERVER_PATH, "--listen", "127.0.0.1:0"}, first_err);
  const std::string line = first.read_line(std::chrono::minutes(5));
  const std::string prefix = "listening on ";
  ASSERT_EQ(line.rfind(prefix, 0), 0u) << "first line: '" << line << "'";
  const std::string address = line.substr(prefix.size());

  const std::string second_err = ::testing::TempDir() + "taken_port_stderr.txt";
  Child second({SHADOW_SERVER_PATH, "--listen", address}, second_err);
  EXPECT_EQ(second.read_line(std::chrono::minutes(5)), "") << "it must not listen";
  const int second_status = second.stop(SIGKILL);
  ASSERT_TRUE(WIFEXITED(second_status));
  EXPECT_EQ(WEXITSTATUS(second_status), 1);
  const int first_status = first.stop(SIGTERM);
  ASSERT_TRUE(WIFEXITED(first_status));
  EXPECT_EQ(WEXITSTATUS(first_status), 0);
  fs::remove_all(cache);

  const std::vector<std::string> cold = lines_of(first_err);
  ASSERT_GE(cold.size(), 2u) << joined(cold);
  EXPECT_EQ(cold[0],
            "shadow-server: building the engine's OpenCL programs (a first start on a device "
            "takes a while; PoCL caches them for the next)...");
  // A cold start says how far it is every 2 s (issue 54), then what it built.
  size_t engine = 1;
  const std::regex building(
      R"(shadow-server: still building \(\d+ s\): \d+ OpenCL programs built so far)");
  while (engine < cold.size() && std::regex_match(cold[engine], building)) ++engine;
  ASSERT_LT(engine, cold.size()) << joined(cold);
  EXPECT_EQ(cold[engine].rfind("shadow-server: engine on ", 0), 0u) << joined(cold);
  EXPECT_NE(cold[engine].find(" kernel profile; "), std::string::npos) << joined(cold);
  const size_t built = cold[engine].find(" OpenCL programs built in ");
  ASSERT_NE(built, std::string::npos) << joined(cold);
  const double seconds = std::stod(cold[engine].substr(built + 26));
  if (seconds >= 2.5) EXPECT_GE(engine, 2u) << "no progress in a " << seconds << " s start";
  for (const std::string& l : cold)
    EXPECT_EQ(l.rfind("shadow-server: ", 0), 0u) << "a line without context: '" << l << "'";

  // The second start: building (progress lines too where it takes 2 s), then the refusal.
  const std::vector<std::string> taken = lines_of(second_err);
  ASSERT_GE(taken.size(), 2u) << joined(taken);
  EXPECT_EQ(taken[0], cold[0]) << joined(taken);
  for (size_t i = 1; i + 1 < taken.size(); ++i)
    EXPECT_TRUE(std::regex_match(taken[i], building)) << joined(taken);
  EXPECT_EQ(taken.back(), "shadow-server: cannot listen on " + address +
                              " (Address already in use: is another server using that port?)")
      << joined(taken);
}

TEST(ServerBinary, ListsEveryDeviceAndTheOneItWouldPick) {
  const auto [list, code] = list_devices();
  EXPECT_EQ(code, 0);
  EXPECT_EQ(list.rfind("platform 0: ", 0), 0u) << list;
  EXPECT_NE(list.find("\n  0:0 "), std::string::npos) << list;
  EXPECT_NE(list.find("[chosen]"), std::string::npos) << list;
  EXPECT_NE(list.find(" compute units, "), std::string::npos) << list;
  EXPECT_NE(list.find(" max buffer, OpenCL C "), std::string::npos) << list;
  if (!has_pocl(list)) GTEST_SKIP() << "PoCL is not installed here";
  EXPECT_NE(list.find("platform 0: Portable Computing Language (The pocl project"),
            std::string::npos)
      << list;
  EXPECT_NE(list.find(" CPU "), std::string::npos) << list;
}

TEST(ServerBinary, RefusesADeviceThatMatchesNothingListingTheDevices) {
  expect_refused({"--device", "nothing-like-this"},
                 "--device 'nothing-like-this' names no OpenCL device");
  expect_refused({"--device", "nothing-like-this"}, "the devices are:\n  0:0 ");
  expect_refused({"--device", "7:0"}, "--device '7:0' names no OpenCL device");
  // Tests and benches name their device in the environment; a bad one is refused the same way.
  ScopedEnv env(shadow::cl::kDeviceEnvironment, "nothing-like-this");
  expect_refused({}, "SHADOW_DEVICE 'nothing-like-this' names no OpenCL device");
}

// PoCL by name (over a SHADOW_DEVICE that names nothing: the flag wins) and by index: the server
// starts on it, says so and renders.
TEST(ServerBinary, StartsOnTheDeviceItIsToldByNameOrIndex) {
  const bool pocl = has_pocl(list_devices().first);
  ScopedEnv env(shadow::cl::kDeviceEnvironment, "nothing-like-this");
  for (const std::string spec : {"pocl", "0:0"}) {
    if (spec == "pocl" && !pocl) continue;
    const std::string err = ::testing::TempDir() + "device_stderr.txt";
    Child server({SHADOW_SERVER_PATH, "--listen", "127.0.0.1:0", "--device", spec}, err);
    const std::string line = server.read_line(std::chrono::minutes(5));
    const std::string prefix = "listening on ";
    ASSERT_EQ(line.rfind(prefix, 0), 0u) << spec << ": first line: '" << line << "'";
    {
      client::ShadowClient client(client::ShadowClient::make_channel(line.substr(prefix.size())));
      EXPECT_EQ(client.render(tiny_proto_request()).textures.size(), 3u) << spec;
    }
    const int status = server.stop(SIGTERM);
    ASSERT_TRUE(WIFEXITED(status)) << spec;
    EXPECT_EQ(WEXITSTATUS(status), 0) << spec;
    std::stringstream text;
    text << std::ifstream(err).rdbuf();
    const std::string want = spec == "pocl" ? "(CPU, Portable Computing Language, driver "
                                            : "shadow-server: engine on 0:0 ";
    EXPECT_NE(text.str().find(want), std::string::npos) << spec << ": " << text.str();
  }
}

// Issue 51: SIGTERM drains. Health turns NOT_SERVING and a new call is refused UNAVAILABLE
// while a render in flight completes; then the server exits 0, saying so.
TEST(ServerBinary, SigtermLetsARenderInFlightFinishAndRefusesNewCalls) {
  const std::string err = ::testing::TempDir() + "drain_stderr.txt";
  Child server({SHADOW_SERVER_PATH, "--listen", "127.0.0.1:0"}, err);
  const std::string line = server.read_line(std::chrono::minutes(5));
  ASSERT_EQ(line.rfind("listening on ", 0), 0u) << "first line: '" << line << "'";
  const std::string address = line.substr(std::string("listening on ").size());
  RenderRequest heavy = small_request({Product::kVisibility});
  heavy.camera.width = heavy.camera.height = 2048;  // about a second of PCSS 64/64 here
  heavy.shadow_map.size = 4096;
  heavy.lights[0].size = 1.0f;
  heavy.filter.kind = FilterKind::kPcss;
  heavy.filter.pcss.blocker_samples = heavy.filter.pcss.filter_samples = 64;
  auto stub = v1::ShadowService::NewStub(client::ShadowClient::make_channel(address));
  grpc::ClientContext context;
  auto reader = stub->Render(&context, convert::to_proto(heavy));
  // Rendering now: its workspace is busy.
  client::ShadowClient watcher(address);
  while (watcher.statistics().workspaces_busy() == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  server.signal(SIGTERM);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  {
    auto late = v1::ShadowService::NewStub(client::ShadowClient::make_channel(address));
    grpc::ClientContext late_context;
    late_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
    v1::Statistics stats;
    EXPECT_EQ(late->GetStatistics(&late_context, v1::StatisticsRequest(), &stats).error_code(),
              grpc::StatusCode::UNAVAILABLE);
  }
  v1::RenderResponse response;
  int messages = 0;
  while (reader->Read(&response)) ++messages;
  const grpc::Status finished = reader->Finish();
  EXPECT_TRUE(finished.ok()) << finished.error_code() << ": " << finished.error_message();
  EXPECT_GT(messages, 1) << "the header and the visibility's chunks";
  const int status = server.stop(0);  // waits: it exits on its own
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  const std::vector<std::string> said = lines_of(err);
  EXPECT_NE(std::find(said.begin(), said.end(), "shadow-server: SIGTERM, shutting down"),
            said.end())
      << joined(said);
  EXPECT_NE(std::find(said.begin(), said.end(), "shadow-server: drained, exiting"), said.end())
      << joined(said);
}

}  // namespace
}  // namespace shadow::test
