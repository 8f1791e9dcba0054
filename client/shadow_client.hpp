// A typed C++ client over the generated ShadowService stub. It reassembles streamed texture
// chunks and converts the reply to the wire vocabulary types (wire/types.hpp).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <grpcpp/grpcpp.h>

#include "shadow/v1/shadow.grpc.pb.h"
#include "wire/result_assembler.hpp"
#include "wire/types.hpp"

namespace shadow::client {

// A failed RPC: the gRPC status code and the server's message (which names the bad field).
class RpcError : public std::runtime_error {
 public:
  RpcError(grpc::StatusCode code, const std::string& message)
      : std::runtime_error(message), code_(code) {}
  grpc::StatusCode code() const { return code_; }

 private:
  grpc::StatusCode code_;
};

// How to reach a server that uses TLS (shadow-server --tls-cert), mTLS (--tls-client-ca) or
// tokens (--auth-tokens). All empty: plaintext. Files are PEM.
struct Credentials {
  std::string tls_ca;    // CA certificates that sign the server's; setting any field means TLS
                         // (empty here: the system's roots)
  std::string tls_cert;  // this client's certificate chain, for mTLS (with tls_key)
  std::string tls_key;
  std::string token;  // sent as "authorization: Bearer TOKEN"
  // The name the server's certificate must carry; empty: the target's host (with several
  // targets, the first one's).
  std::string tls_server_name;
  bool tls() const {
    return !tls_ca.empty() || !tls_cert.empty() || !tls_key.empty() || !token.empty();
  }
};

class ShadowClient {
 public:
  // Name under which the server reports health (grpc.health.v1).
  static constexpr const char* kServiceName = "shadow.v1.ShadowService";
  // Largest reply message accepted by make_channel(); the server sends 2 MiB chunks.
  static constexpr int kMaxReceiveBytes = 64 << 20;

  // How render() and render_sequence() resume a stream that broke off (below): before the n-th
  // resume of a call (n = 0, 1, ...; a sequence counts from its last stream that delivered a
  // frame) it waits a pause drawn uniformly from
  // [0, min(kResumeBackoffMax, kResumeBackoffInitial * kResumeBackoffMultiplier^n)] ("full
  // jitter": clients cut off by the same crash do not all come back at once), then sends the
  // stream again with gRPC's wait_for_ready, so that while the server is down (restarting) the
  // call waits for the channel to connect instead of failing at once. Resumes go on while the
  // call's deadline allows, however many it takes; none starts whose pause would pass the
  // deadline (the stream's error is thrown then). make_channel() caps gRPC's reconnect backoff
  // (GRPC_ARG_MAX_RECONNECT_BACKOFF_MS) at kResumeBackoffMax too, so a server that comes back is
  // seen within about that long; a channel of your own keeps gRPC's (up to 120 s).
  static constexpr std::chrono::milliseconds kResumeBackoffInitial{100};
  static constexpr int kResumeBackoffMultiplier = 2;
  static constexpr std::chrono::milliseconds kResumeBackoffMax{2000};

  // A channel with a receive limit sized for chunks and no send limit (scenes); plaintext unless
  // `credentials` ask for TLS. `servers`: "HOST:PORT", several "IP:PORT,IP:PORT" or a gRPC target
  // such as "dns:///NAME:PORT" (channel_target.hpp). The service config
  // (client/service_config.json) balances calls round_robin over every address and retries a
  // call that fails UNAVAILABLE before its first reply (another replica, up to 4 attempts; the
  // request is kept for that up to kRetryBufferBytes). Throws std::invalid_argument for a bad
  // server list, std::runtime_error for an unreadable PEM file.
  static std::shared_ptr<grpc::Channel> make_channel(const std::string& servers,
                                                     const Credentials& credentials = {});
  static constexpr int kRetryBufferBytes = 64 << 20;

  // e.g. "127.0.0.1:50051", "127.0.0.1:5001,127.0.0.1:5002", "dns:///shadow:50051"
  explicit ShadowClient(const std::string& servers, const Credentials& credentials = {});
  // A channel of your own must accept messages of at least one chunk (gRPC's 4 MiB default does).
  explicit ShadowClient(std::shared_ptr<grpc::Channel> channel);

  // Called on the reading thread after each message with the stream so far and the texture that
  // grew (ResultAssembler::kNoTexture after the header), so a caller can use each texture's
  // bytes while the rest arrive. What it throws cancels the call and propagates. When a stream
  // fails or is restarted, it is called once more with kStreamDiscarded before the stream's
  // storage is freed: stop using those bytes (what it throws then is ignored).
  using Progress = std::function<void(const convert::ResultAssembler& stream, size_t texture)>;
  static constexpr size_t kStreamDiscarded = size_t(-2);

  // Sends the request and returns every product, reassembled. Throws RpcError: the server's
  // status, or DATA_LOSS when the stream breaks the protocol (gaps, overlaps, missing bytes,
  // a compressed chunk that does not decompress to its declared size).
  // A request carries its scene's id as "x-scene-id" metadata (for a proxy's consistent hash);
  // a request by scene_id that the server does not hold is retried as upload_scene() says. A stream
  // that breaks off after replies began, UNAVAILABLE (its replica died) or INTERNAL (a proxy reset
  // it: nginx does when its upstream dies), is sent again from the start, with the backoff above,
  // until the deadline; a resumed stream that fails the same way, even before its first reply
  // (the server may still be on its way back), is resumed again. gRPC's retry policy cannot retry
  // a call once replies arrived. `progress` then sees the new stream from its header. (The server
  // renders everything before its header, so nothing but the path to it fails after that.)
  RenderResult render(const v1::RenderRequest& request,
                      std::chrono::milliseconds deadline = std::chrono::minutes(5),
                      const Progress& progress = {});
  RenderResult render(const RenderRequest& request,
                      std::chrono::milliseconds deadline = std::chrono::minutes(5));

  // UploadScene: sends the scene's canonical serialization in chunks of kUploadChunkBytes and
  // returns its id (wire/scene_id.hpp; checked against the id computed here). The client keeps
  // the scene, so that a later request naming the id that the server no longer holds (NOT_FOUND:
  // evicted, or another replica) uploads it again and retries, once (scene_reuploads()).
  std::string upload_scene(const v1::Scene& scene,
                           std::chrono::milliseconds deadline = std::chrono::minutes(5));
  static constexpr size_t kUploadChunkBytes = 2 << 20;

  // RenderSequence: calls `frame` with each frame's result (RenderResult::frame, ::reused) as
  // soon as its last chunk arrives, in order; what `frame` throws cancels the call. Throws
  // RpcError as render(). A stream that breaks off as in render(), before or after its first
  // frame, is sent again with the frames not delivered yet (with the backoff above, until the
  // deadline), so every frame arrives once; a replica that does not hold the scene gets it
  // uploaded again as upload_scene() says.
  using FrameDone = std::function<void(RenderResult&& frame)>;
  void render_sequence(const v1::SequenceRequest& request, const FrameDone& frame,
                       std::chrono::milliseconds deadline = std::chrono::minutes(30));

  // Called with each Progress message of render() and render_sequence(), which the server sends
  // where the request asks for them (RenderRequest.progress; a sequence's base). Empty: they are
  // dropped. What it throws cancels the call.
  using WorkProgress = std::function<void(const v1::Progress&)>;
  void on_progress(WorkProgress progress) { work_progress_ = std::move(progress); }

  // GetStatistics: the server's counts and times (with tokens: this tenant's). Throws RpcError.
  v1::Statistics statistics(std::chrono::milliseconds deadline = std::chrono::seconds(10));

  // Estimate: admission's price of a request or a sequence, without rendering (issue 51).
  // Throws RpcError (INVALID_ARGUMENT for what Render would refuse as invalid).
  v1::Price estimate(const v1::EstimateRequest& request,
                     std::chrono::milliseconds deadline = std::chrono::seconds(30));

  // True when grpc.health.v1 reports SERVING for "shadow.v1.ShadowService".
  bool healthy(std::chrono::milliseconds deadline = std::chrono::seconds(2));

  // Streams this client sent again after a broken reply (all calls so far).
  uint64_t stream_restarts() const { return stream_restarts_; }
  // Scenes this client uploaded again because a request by id found the server without them.
  uint64_t scene_reuploads() const { return scene_reuploads_; }

 private:
  // render() with restarts of a broken stream.
  RenderResult render_restarting(const v1::RenderRequest& request, const std::string& scene_id,
                                 std::chrono::system_clock::time_point deadline,
                                 const Progress& progress);
  // One stream of render(); throws RpcError. `replied`: whether any reply message arrived.
  // `resumed`: the call waits for the channel to connect (see kResumeBackoffInitial).
  RenderResult render_once(const v1::RenderRequest& request, const std::string& scene_id,
                           std::chrono::system_clock::time_point deadline, const Progress& progress,
                           bool resumed, bool& replied);

  // Runs `call` (a request by `scene_id`, or any request when it is empty); when the server does
  // not hold the scene and this client uploaded it, uploads it again and runs `call` once more.
  template <class Call>
  auto with_scene(const std::string& scene_id, std::chrono::system_clock::time_point deadline,
                  Call call) -> decltype(call());

  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::ShadowService::Stub> stub_;
  std::atomic<uint64_t> stream_restarts_{0};
  // A Progress message goes to work_progress_ (if any): true; anything else: false.
  bool took_progress(const v1::RenderResponse& response) const;
  WorkProgress work_progress_;
  std::atomic<uint64_t> scene_reuploads_{0};
  std::mutex uploaded_mutex_;
  std::map<std::string, std::shared_ptr<const v1::Scene>> uploaded_;  // by id
};

}  // namespace shadow::client
