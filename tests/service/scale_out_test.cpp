// Scale-out on loopback with engines that exist (issue 16.2): a 60-frame sequence through
//  - nginx (deploy/nginx.conf as shipped, its addresses replaced) in front of three replicas:
//    every frame of the scene goes to one replica (consistent hash of x-scene-id), which is
//    killed with SIGKILL while it streams frame 30;
//  - three replicas dialled directly with round_robin (the client library's service config):
//    the replica that served frame 27 is killed while frame 30 streams (with all three ready,
//    round_robin gives it frame 30 too).
//  - nginx again, the same 60 frames as one RenderSequence of an uploaded scene, the replica
//    holding it killed after frame 30 arrived: the client resumes with the frames it lacks and
//    uploads the scene again to the replica nginx now picks.
// Every frame must arrive once and be bit-identical to a single-server run. The retries (nginx's
// next upstream, gRPC's retry policy as the replicas saw it in grpc-previous-rpc-attempts, the
// client's stream restarts) are printed, not asserted: which path recovers a frame depends on
// when the kernel tells each party of the dead socket, and the test must not depend on timing.
#include <signal.h>
#include <sys/socket.h>

#include <netinet/in.h>

#include <arpa/inet.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "child_process.hpp"
#include "shadow_client.hpp"
#include "test_scene.hpp"
#include "wire/convert.hpp"

namespace shadow::test {
namespace {

namespace fs = std::filesystem;
constexpr int kFrames = 60;
constexpr int kKillFrame = 30;

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> lines_with(const fs::path& path, const std::string& needle) {
  std::vector<std::string> out;
  std::istringstream in(read_text(path));
  for (std::string line; std::getline(in, line);)
    if (line.find(needle) != std::string::npos) out.push_back(line);
  return out;
}

// A port nothing listens on now (for nginx, which cannot report the port it picked).
int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof a;
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&a), &size) != 0)
    throw std::runtime_error("no free port");
  close(fd);
  return ntohs(a.sin_port);
}

struct Replica {
  std::unique_ptr<Child> process;
  std::string address;  // "127.0.0.x:PORT"
  fs::path log;         // its --log-format json lines
};

Replica start_replica(const std::string& ip, const fs::path& log) {
  Replica r;
  r.log = log;
  r.process = std::make_unique<Child>(
      std::vector<std::string>{SHADOW_SERVER_PATH, "--listen", ip + ":0", "--log-format", "json",
                               "--max-connection-age", "3600"},
      log.string());
  const std::string line = r.process->read_line(std::chrono::minutes(3));
  if (line.rfind("listening on ", 0) != 0)
    throw std::runtime_error("replica on " + ip + " did not start: " + read_text(log));
  r.address = line.substr(std::strlen("listening on "));
  return r;
}

// Render calls a replica logged, and the sum of their grpc-previous-rpc-attempts.
struct LogCounts {
  int renders = 0, retried_attempts = 0;
};
LogCounts count_log(const Replica& r) {
  LogCounts c;
  static const std::regex attempts("\"previous_attempts\":([0-9]+)");
  for (const std::string& line : lines_with(r.log, "\"event\":\"render\"")) {
    ++c.renders;
    std::smatch m;
    if (std::regex_search(line, m, attempts)) c.retried_attempts += std::stoi(m[1]);
  }
  return c;
}

// Frame k of the sequence: the test scene seen from a camera circling it with a 1024^2 map;
// frame 30 asks for a 4096^2 map (64 MiB), more than the sockets, nginx and the HTTP/2 windows
// hold (a 2048^2 reply had passed nginx whole before the first chunk reached the client), so a
// replica killed at its first chunk has not sent the whole reply yet.
v1::RenderRequest frame(int k) {
  v1::RenderRequest r =
      convert::to_proto(small_request({Product::kShadowMap, Product::kVisibility}));
  const double a = 2 * M_PI * k / kFrames;
  r.mutable_camera()->mutable_eye()->set_x(float(12 * std::sin(a)));
  r.mutable_camera()->mutable_eye()->set_z(float(12 * std::cos(a)));
  r.mutable_shadow_map()->set_size(k == kKillFrame ? 4096 : 1024);
  return r;
}

// The textures' bytes and matrices, to compare frames bit for bit.
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

// Runs the sequence; `at_first_chunk_of_kill_frame` runs once, inside frame 30's stream.
// Returns how many frames came back equal to `reference` (each frame is asked for once).
int run_sequence(client::ShadowClient& client,
                 const std::vector<std::vector<std::string>>& reference,
                 const std::function<void(int frame)>& after_frame,
                 const std::function<void()>& at_first_chunk_of_kill_frame) {
  int equal = 0;
  for (int k = 0; k < kFrames; ++k) {
    bool fired = false;
    client::ShadowClient::Progress progress;
    if (k == kKillFrame)
      progress = [&](const convert::ResultAssembler&, size_t texture) {
        if (!fired && texture != convert::ResultAssembler::kNoTexture &&
            texture != client::ShadowClient::kStreamDiscarded) {
          fired = true;
          at_first_chunk_of_kill_frame();
        }
      };
    const RenderResult result = client.render(frame(k), std::chrono::minutes(5), progress);
    const bool same = fingerprint(result) == reference[k];
    EXPECT_TRUE(same) << "frame " << k << " differs from the single-server run";
    equal += same;
    if (after_frame) after_frame(k);
  }
  return equal;
}

class ScaleOut : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("scale_out_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "nginx" / "logs");
    fs::create_directories(dir_ / "nginx" / "tmp");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The single-server run every other run must reproduce, from `replica` alone.
  std::vector<std::vector<std::string>> reference_run(const Replica& replica) {
    client::ShadowClient client(replica.address);
    std::vector<std::vector<std::string>> out;
    for (int k = 0; k < kFrames; ++k) out.push_back(fingerprint(client.render(frame(k))));
    return out;
  }

  fs::path dir_;
};

// deploy/nginx.conf as shipped, with `replicas` behind it; returns its address once a health
// check passes through it. The process stops (SIGTERM) with `nginx`.
std::string start_nginx(const fs::path& prefix, const std::vector<Replica>& replicas,
                        std::unique_ptr<Child>& nginx) {
  std::string conf = read_text(fs::path(SHADOW_DEPLOY_DIR) / "nginx.conf");
  const std::string front = "127.0.0.1:" + std::to_string(free_port());
  const std::vector<std::pair<std::string, std::string>> swaps = {
      {"listen 127.0.0.1:50060", "listen " + front},
      {"server 127.0.0.1:50061;", "server " + replicas[0].address + ";"},
      {"server 127.0.0.1:50062;", "server " + replicas[1].address + ";"},
      {"server 127.0.0.1:50063;", "server " + replicas[2].address + ";"}};
  for (const auto& [from, to] : swaps) {
    const size_t at = conf.find(from);
    if (at == std::string::npos) throw std::runtime_error("deploy/nginx.conf lacks '" + from + "'");
    conf.replace(at, from.size(), to);
  }
  std::ofstream(prefix / "nginx.conf") << conf;
  nginx =
      std::make_unique<Child>(std::vector<std::string>{NGINX_PATH, "-p", prefix.string(), "-c",
                                                       (prefix / "nginx.conf").string(), "-e",
                                                       (prefix / "logs" / "error.log").string()},
                              (prefix / "stderr.txt").string());
  nginx->set_exit_signal(SIGTERM);
  client::ShadowClient probe(front);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(1);
  while (!probe.healthy()) {  // nginx is up when a health check passes through it
    if (std::chrono::steady_clock::now() > give_up)
      throw std::runtime_error("nginx did not come up: " + read_text(prefix / "stderr.txt") +
                               read_text(prefix / "logs" / "error.log"));
    usleep(100 * 1000);
  }
  return front;
}

TEST_F(ScaleOut, NginxConsistentHashSurvivesAKilledReplica) {
  std::vector<Replica> replicas;
  for (const char* ip : {"127.0.0.2", "127.0.0.3", "127.0.0.4"})
    replicas.push_back(start_replica(ip, dir_ / (std::string("replica-") + ip + ".log")));
  const auto reference = reference_run(replicas[0]);

  const fs::path prefix = dir_ / "nginx";
  std::unique_ptr<Child> nginx;
  const std::string front = start_nginx(prefix, replicas, nginx);
  client::ShadowClient client(front);

  // Which replica each Render went to, from nginx's access log ("upstream=A, B" after a retry).
  auto upstreams = [&] {
    std::vector<std::string> out;
    static const std::regex field("upstream=([^ ]+( : [^ ]+|, [^ ]+)*) scene=");
    for (const std::string& line : lines_with(prefix / "logs" / "access.log", "/Render ")) {
      std::smatch m;
      out.push_back(std::regex_search(line, m, field) ? m[1].str() : "?");
    }
    return out;
  };
  std::string serving;
  size_t killed = replicas.size();
  auto kill_serving = [&] {
    const std::vector<std::string> before = upstreams();
    ASSERT_EQ(before.size(), size_t(kKillFrame));
    serving = before[0];
    for (const std::string& u : before) EXPECT_EQ(u, serving) << "the scene moved between replicas";
    for (size_t i = 0; i < replicas.size(); ++i)
      if (replicas[i].address == serving) killed = i;
    ASSERT_LT(killed, replicas.size()) << "nginx sent the scene to " << serving;
    replicas[killed].process->stop(SIGKILL);
  };
  const int equal = run_sequence(client, reference, nullptr, kill_serving);
  EXPECT_EQ(equal, kFrames);

  const std::vector<std::string> all = upstreams();
  std::set<std::string> after;
  int nginx_retries = 0;
  for (size_t k = 0; k < all.size(); ++k) {
    if (all[k].find(',') != std::string::npos || all[k].find(" : ") != std::string::npos)
      ++nginx_retries;
    if (k > size_t(kKillFrame)) after.insert(all[k].substr(all[k].rfind(' ') + 1));
  }
  int grpc_retries = 0;
  for (const Replica& r : replicas) grpc_retries += count_log(r).retried_attempts;
  std::printf(
      "nginx: %d frames, all %d before the kill on %s (killed with SIGKILL at frame %d's first "
      "chunk), after it on %s; %zu Render calls reached nginx; nginx tried another replica for "
      "%d; gRPC retry-policy attempts seen by the replicas: %d; client stream restarts: %llu; "
      "frames equal to the single-server run: %d\n",
      kFrames, kKillFrame, serving.c_str(), kKillFrame,
      after.empty() ? "-" : after.begin()->c_str(), all.size(), nginx_retries, grpc_retries,
      (unsigned long long)client.stream_restarts(), equal);
  EXPECT_EQ(after.size(), 1u) << "after the kill the scene should stay on one replica";
  EXPECT_EQ(after.count(serving), 0u);
}

// The same shot as one RenderSequence of an uploaded scene, through nginx: the replica holding
// the scene is killed with SIGKILL once frame 30 has arrived. The client resumes with the frames
// it lacks; nginx's consistent hash moves the scene id to another replica, which does not hold
// the scene (NOT_FOUND), so the client uploads it again there. Every frame arrives once,
// bit-identical to the single-server run.
v1::SequenceRequest shot() {
  v1::SequenceRequest s;
  *s.mutable_base() = frame(0);
  for (int k = 0; k < kFrames; ++k) *s.add_frames()->mutable_camera() = frame(k).camera();
  return s;
}

TEST_F(ScaleOut, NginxSequenceResumesOnAnotherReplica) {
  std::vector<Replica> replicas;
  for (const char* ip : {"127.0.0.9", "127.0.0.10", "127.0.0.11"})
    replicas.push_back(start_replica(ip, dir_ / (std::string("replica-") + ip + ".log")));
  std::vector<std::vector<std::string>> reference;
  client::ShadowClient(replicas[0].address).render_sequence(shot(), [&](RenderResult&& r) {
    reference.push_back(fingerprint(r));
  });
  ASSERT_EQ(reference.size(), size_t(kFrames));

  const fs::path prefix = dir_ / "nginx";
  std::unique_ptr<Child> nginx;
  client::ShadowClient client(start_nginx(prefix, replicas, nginx));
  v1::SequenceRequest by_id = shot();
  const std::string id = client.upload_scene(by_id.base().scene());
  by_id.mutable_base()->set_scene_id(id);
  int holder = -1;  // the replica the upload went to
  for (size_t i = 0; i < replicas.size(); ++i)
    if (!lines_with(replicas[i].log, "\"event\":\"upload\"").empty()) holder = int(i);
  ASSERT_GE(holder, 0);

  std::vector<int> arrived(kFrames, 0);
  int equal = 0;
  client.render_sequence(by_id, [&](RenderResult&& r) {
    ASSERT_LT(r.frame, uint32_t(kFrames));
    ++arrived[r.frame];
    equal += fingerprint(r) == reference[r.frame];
    if (r.frame == uint32_t(kKillFrame)) replicas[size_t(holder)].process->stop(SIGKILL);
  });
  EXPECT_EQ(arrived, std::vector<int>(kFrames, 1)) << "every frame once";
  EXPECT_EQ(equal, kFrames);
  EXPECT_GE(client.stream_restarts(), 1u);
  EXPECT_EQ(client.scene_reuploads(), 1u);
  int sequences_after = 0, uploads_after = 0;
  for (size_t i = 0; i < replicas.size(); ++i) {
    if (int(i) == holder) continue;
    sequences_after += int(lines_with(replicas[i].log, "\"event\":\"sequence\"").size());
    uploads_after += int(lines_with(replicas[i].log, "\"event\":\"upload\"").size());
  }
  std::printf(
      "nginx sequence: %d frames by scene id on %s, killed with SIGKILL after frame %d arrived; "
      "client stream restarts %llu, scene re-uploads %llu; the other replicas logged %d sequence "
      "and %d upload calls; frames equal to the single-server run: %d, each once\n",
      kFrames, replicas[size_t(holder)].address.c_str(), kKillFrame,
      (unsigned long long)client.stream_restarts(), (unsigned long long)client.scene_reuploads(),
      sequences_after, uploads_after, equal);
}

TEST_F(ScaleOut, RoundRobinSurvivesAKilledReplica) {
  std::vector<Replica> replicas;
  for (const char* ip : {"127.0.0.5", "127.0.0.6", "127.0.0.7"})
    replicas.push_back(start_replica(ip, dir_ / (std::string("replica-") + ip + ".log")));
  Replica single = start_replica("127.0.0.8", dir_ / "single.log");
  const auto reference = reference_run(single);

  client::ShadowClient client(replicas[0].address + "," + replicas[1].address + "," +
                              replicas[2].address);
  // Who served each frame: the replica whose log grew during it.
  std::vector<int> served;
  std::vector<int> counts(replicas.size(), 0);
  auto after_frame = [&](int) {
    int who = -1;
    for (size_t i = 0; i < replicas.size(); ++i) {
      const int n = count_log(replicas[i]).renders;
      if (n > counts[i]) who = int(i);
      counts[i] = n;
    }
    served.push_back(who);
  };
  int killed = -1;
  auto kill_predicted = [&] {
    killed = served[kKillFrame - 3];  // round_robin over three: frame 30's replica served 27
    replicas[size_t(killed)].process->stop(SIGKILL);
  };
  const int equal = run_sequence(client, reference, after_frame, kill_predicted);
  EXPECT_EQ(equal, kFrames);

  std::map<int, int> before, after;
  for (int k = 0; k < int(served.size()); ++k) ++(k < kKillFrame ? before : after)[served[k]];
  int grpc_retries = 0;
  for (size_t i = 0; i < replicas.size(); ++i)
    if (int(i) != killed) grpc_retries += count_log(replicas[i]).retried_attempts;
  auto show = [&](const std::map<int, int>& m) {
    std::string s;
    for (const auto& [who, n] : m)
      s += (s.empty() ? "" : ", ") + (who < 0 ? std::string("?") : replicas[who].address) + ": " +
           std::to_string(n);
    return s;
  };
  std::printf(
      "round_robin: frames per replica before the kill {%s}, after {%s}; killed %s with SIGKILL "
      "at frame %d's first chunk; gRPC retry-policy attempts seen by the survivors: %d; client "
      "stream restarts: %llu; frames equal to the single-server run: %d\n",
      show(before).c_str(), show(after).c_str(), replicas[size_t(killed)].address.c_str(),
      kKillFrame, grpc_retries, (unsigned long long)client.stream_restarts(), equal);
}

}  // namespace
}  // namespace shadow::test
