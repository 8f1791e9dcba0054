#include "shadow_client.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <new>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include "channel_target.hpp"
#include "grpc/health/v1/health.grpc.pb.h"
#include "service_config.hpp"
#include "wire/convert.hpp"
#include "wire/result_assembler.hpp"
#include "wire/scene_id.hpp"

namespace shadow::client {
namespace {

std::chrono::system_clock::time_point after(std::chrono::milliseconds deadline) {
  return std::chrono::system_clock::now() + deadline;
}

// Sleeps before the `step`-th resume of a call (from 0; ShadowClient::kResumeBackoffInitial says
// how long). False, without sleeping, when the pause would reach `deadline`: no resume is left.
bool pause_before_resume(int step, std::chrono::system_clock::time_point deadline) {
  using Ms = std::chrono::milliseconds;
  const double ceiling = std::min(
      double(ShadowClient::kResumeBackoffMax.count()),
      double(ShadowClient::kResumeBackoffInitial.count()) *
          std::pow(double(ShadowClient::kResumeBackoffMultiplier), double(std::min(step, 64))));
  thread_local std::minstd_rand random{std::random_device{}()};
  const Ms pause(std::uniform_int_distribution<Ms::rep>(0, Ms::rep(ceiling))(random));
  if (std::chrono::system_clock::now() + pause >= deadline) return false;
  std::this_thread::sleep_for(pause);
  return true;
}

std::string read_pem(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(std::string("cannot read ") + what + " " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::shared_ptr<grpc::ChannelCredentials> channel_credentials(const Credentials& c) {
  if (!c.tls()) return grpc::InsecureChannelCredentials();
  grpc::SslCredentialsOptions ssl;
  if (!c.tls_ca.empty()) ssl.pem_root_certs = read_pem(c.tls_ca, "the CA file");
  if (!c.tls_cert.empty() || !c.tls_key.empty()) {
    if (c.tls_cert.empty() || c.tls_key.empty())
      throw std::runtime_error("a client certificate needs both its file and its key");
    ssl.pem_cert_chain = read_pem(c.tls_cert, "the certificate file");
    ssl.pem_private_key = read_pem(c.tls_key, "the key file");
  }
  std::shared_ptr<grpc::ChannelCredentials> tls = grpc::SslCredentials(ssl);
  if (c.token.empty()) return tls;
  return grpc::CompositeChannelCredentials(tls, grpc::AccessTokenCredentials(c.token));
}

}  // namespace

std::shared_ptr<grpc::Channel> ShadowClient::make_channel(const std::string& servers,
                                                          const Credentials& credentials) {
  const std::string target = channel_target(servers);
  grpc::ChannelArguments args;
  // Chunks are 2 MiB; allow a server configured with bigger ones. Requests carry whole scenes.
  args.SetMaxReceiveMessageSize(kMaxReceiveBytes);
  args.SetMaxSendMessageSize(-1);
  args.SetServiceConfigJSON(kServiceConfigJson);
  args.SetInt(GRPC_ARG_ENABLE_RETRIES, 1);
  // gRPC keeps a call's request for its retries only up to this size (256 KiB by default).
  args.SetInt(GRPC_ARG_PER_RPC_RETRY_BUFFER_SIZE, kRetryBufferBytes);
  // A resumed stream waits for the channel to connect; gRPC's reconnect backoff grows to 120 s
  // by default, which would see a restarted server that late.
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, int(kResumeBackoffMax.count()));
  // Several addresses have no one name for TLS to check: the first host's, unless told.
  if (!credentials.tls_server_name.empty())
    args.SetString(GRPC_ARG_DEFAULT_AUTHORITY, credentials.tls_server_name);
  else if (target != servers)
    args.SetString(GRPC_ARG_DEFAULT_AUTHORITY, first_host(servers));
  return grpc::CreateCustomChannel(target, channel_credentials(credentials), args);
}

ShadowClient::ShadowClient(const std::string& servers, const Credentials& credentials)
    : ShadowClient(make_channel(servers, credentials)) {}

ShadowClient::ShadowClient(std::shared_ptr<grpc::Channel> channel)
    : channel_(std::move(channel)), stub_(v1::ShadowService::NewStub(channel_)) {}

template <class Call>
auto ShadowClient::with_scene(const std::string& id, std::chrono::system_clock::time_point deadline,
                              Call call) -> decltype(call()) {
  try {
    return call();
  } catch (const RpcError& e) {
    if (id.empty() || e.code() != grpc::StatusCode::NOT_FOUND) throw;
    std::shared_ptr<const v1::Scene> scene;
    {
      std::lock_guard<std::mutex> lock(uploaded_mutex_);
      const auto it = uploaded_.find(id);
      if (it == uploaded_.end()) throw;  // not ours to upload
      scene = it->second;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::system_clock::now());
    upload_scene(*scene, std::max(left, std::chrono::milliseconds(1)));
    ++scene_reuploads_;
    return call();
  }
}

std::string ShadowClient::upload_scene(const v1::Scene& scene, std::chrono::milliseconds deadline) {
  std::string bytes;
  {
    google::protobuf::io::StringOutputStream stream(&bytes);
    google::protobuf::io::CodedOutputStream out(&stream);
    out.SetSerializationDeterministic(true);
    scene.SerializeToCodedStream(&out);
  }
  const std::string id = scene_id(scene);
  grpc::ClientContext context;
  context.set_deadline(after(deadline));
  context.AddMetadata(kSceneIdHeader, id);
  v1::SceneRef reply;
  std::unique_ptr<grpc::ClientWriter<v1::SceneUpload>> writer =
      stub_->UploadScene(&context, &reply);
  v1::SceneUpload chunk;
  chunk.set_total_bytes(bytes.size());
  for (size_t offset = 0; offset < bytes.size(); offset += kUploadChunkBytes) {
    chunk.set_data(bytes.substr(offset, kUploadChunkBytes));
    if (!writer->Write(chunk)) break;  // the server ended the call: Finish says why
    chunk.clear_total_bytes();
  }
  writer->WritesDone();
  const grpc::Status status = writer->Finish();
  if (!status.ok()) throw RpcError(status.error_code(), status.error_message());
  if (reply.scene_id() != id)
    throw RpcError(grpc::StatusCode::DATA_LOSS,
                   "the server's scene id " + reply.scene_id() + " is not the scene's " + id);
  std::lock_guard<std::mutex> lock(uploaded_mutex_);
  uploaded_.try_emplace(id, std::make_shared<const v1::Scene>(scene));
  return id;
}

RenderResult ShadowClient::render(const v1::RenderRequest& request,
                                  std::chrono::milliseconds deadline, const Progress& progress) {
  const auto until = after(deadline);
  if (request.has_scene())
    return render_restarting(request, scene_id(request.scene()), until, progress);
  return with_scene(request.scene_id(), until, [&] {
    return render_restarting(request, request.scene_id(), until, progress);
  });
}

RenderResult ShadowClient::render_restarting(const v1::RenderRequest& request,
                                             const std::string& scene_id,
                                             std::chrono::system_clock::time_point until,
                                             const Progress& progress) {
  for (int resumes = 0;; ++resumes) {
    bool replied = false;
    try {
      return render_once(request, scene_id, until, progress, resumes > 0, replied);
    } catch (const RpcError& e) {
      // The server renders everything before its header, so once replies came only the path to
      // it can fail: a dead replica (UNAVAILABLE) or a proxy whose upstream died (nginx resets
      // the stream: INTERNAL, "Received RST_STREAM with error code 2"). Once resuming, the same
      // errors before a reply mean the server is not back yet (a proxy answers for it).
      const bool broke =
          e.code() == grpc::StatusCode::UNAVAILABLE || e.code() == grpc::StatusCode::INTERNAL;
      if (!broke || !(replied || resumes > 0) || !pause_before_resume(resumes, until)) throw;
      ++stream_restarts_;
    }
  }
}

RenderResult ShadowClient::render_once(const v1::RenderRequest& request,
                                       const std::string& scene_id,
                                       std::chrono::system_clock::time_point deadline,
                                       const Progress& progress, bool resumed, bool& replied) {
  grpc::ClientContext context;
  context.set_deadline(deadline);
  context.set_wait_for_ready(resumed);
  if (!scene_id.empty()) context.AddMetadata(kSceneIdHeader, scene_id);
  std::unique_ptr<grpc::ClientReader<v1::RenderResponse>> reader = stub_->Render(&context, request);

  convert::ResultAssembler assembler;
  // Unless the stream completes, tells `progress` before `assembler` frees what the stream
  // received (declared after it, so destroyed before it).
  struct Discard {
    const Progress& progress;
    const convert::ResultAssembler& assembler;
    bool completed = false;
    ~Discard() {
      if (completed || !progress) return;
      try {
        progress(assembler, kStreamDiscarded);
      } catch (...) {  // the stream failed already; that error is the one that propagates
      }
    }
  } discard{progress, assembler};
  v1::RenderResponse response;
  // A broken stream is our DATA_LOSS; out of memory is RESOURCE_EXHAUSTED. Either way the call
  // is cancelled and drained so that Finish() returns.
  auto drain = [&] {
    context.TryCancel();
    while (reader->Read(&response)) {
    }
    reader->Finish();
  };
  auto abandon = [&](grpc::StatusCode code, const std::string& message) {
    drain();
    return RpcError(code, message);
  };
  try {
    while (reader->Read(&response)) {
      replied = true;
      if (took_progress(response)) continue;
      const size_t texture = assembler.add(response);
      if (progress) progress(assembler, texture);
    }
  } catch (const convert::StreamError& e) {
    throw abandon(grpc::StatusCode::DATA_LOSS, std::string("bad Render stream: ") + e.what());
  } catch (const std::bad_alloc&) {
    throw abandon(grpc::StatusCode::RESOURCE_EXHAUSTED, "out of memory for the textures");
  } catch (...) {  // the caller's progress failed
    drain();
    throw;
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) throw RpcError(status.error_code(), status.error_message());
  try {
    RenderResult result = assembler.finish();
    discard.completed = true;
    return result;
  } catch (const convert::StreamError& e) {
    throw RpcError(grpc::StatusCode::DATA_LOSS, std::string("bad Render stream: ") + e.what());
  }
}

bool ShadowClient::took_progress(const v1::RenderResponse& response) const {
  if (!response.has_progress()) return false;
  if (work_progress_) work_progress_(response.progress());
  return true;
}

RenderResult ShadowClient::render(const RenderRequest& request,
                                  std::chrono::milliseconds deadline) {
  return render(convert::to_proto(request), deadline);
}

void ShadowClient::render_sequence(const v1::SequenceRequest& request, const FrameDone& frame,
                                   std::chrono::milliseconds deadline) {
  const auto until = after(deadline);
  const v1::RenderRequest& base = request.base();
  const std::string id = base.has_scene() ? scene_id(base.scene()) : base.scene_id();
  int delivered = 0;     // frames handed to `frame`
  int backoff_step = 0;  // resumes since a stream last delivered a frame
  for (int resumes = 0;; ++resumes) {
    // After a break: the frames not delivered yet, numbered from `first` on.
    const int first = delivered;
    if (first == request.frames_size() && first > 0) return;
    v1::SequenceRequest rest;
    if (first > 0) {
      *rest.mutable_base() = base;
      rest.mutable_frames()->CopyFrom(request.frames());
      rest.mutable_frames()->DeleteSubrange(0, first);
    }
    const v1::SequenceRequest& send = first > 0 ? rest : request;
    const auto once = [&] {
      grpc::ClientContext context;
      context.set_deadline(until);
      context.set_wait_for_ready(resumes > 0);
      if (!id.empty()) context.AddMetadata(kSceneIdHeader, id);
      std::unique_ptr<grpc::ClientReader<v1::RenderResponse>> reader =
          stub_->RenderSequence(&context, send);
      std::optional<convert::ResultAssembler> assembler;
      v1::RenderResponse response;
      const auto deliver = [&] {
        if (!assembler) return;
        RenderResult result = assembler->finish();
        assembler.reset();
        result.frame += uint32_t(first);
        ++delivered;
        frame(std::move(result));
      };
      try {
        while (reader->Read(&response)) {
          if (took_progress(response)) continue;
          if (response.has_header()) deliver();  // the previous frame is complete
          if (!assembler) assembler.emplace();
          assembler->add(response);
        }
      } catch (...) {
        context.TryCancel();
        while (reader->Read(&response)) {
        }
        reader->Finish();
        try {
          throw;
        } catch (const convert::StreamError& e) {
          throw RpcError(grpc::StatusCode::DATA_LOSS,
                         std::string("bad sequence stream: ") + e.what());
        } catch (const std::bad_alloc&) {
          throw RpcError(grpc::StatusCode::RESOURCE_EXHAUSTED, "out of memory for the textures");
        }
      }
      const grpc::Status status = reader->Finish();
      if (!status.ok()) throw RpcError(status.error_code(), status.error_message());
      try {
        deliver();
      } catch (const convert::StreamError& e) {
        throw RpcError(grpc::StatusCode::DATA_LOSS,
                       std::string("bad sequence stream: ") + e.what());
      }
    };
    try {
      // The server looks the scene up before it renders: a NOT_FOUND comes before any frame.
      with_scene(base.has_scene() ? "" : id, until, [&] {
        once();
        return 0;
      });
      return;
    } catch (const RpcError& e) {
      // As render(): a replica that died (UNAVAILABLE) or a proxy that reset the stream
      // (INTERNAL); the frames delivered stay delivered, the rest is asked for again. A stream
      // that delivered frames was healthy: the next pause starts from the shortest again.
      const bool broke =
          e.code() == grpc::StatusCode::UNAVAILABLE || e.code() == grpc::StatusCode::INTERNAL;
      if (delivered > first) backoff_step = 0;
      if (!broke || !pause_before_resume(backoff_step++, until)) throw;
      ++stream_restarts_;
    }
  }
}

v1::Statistics ShadowClient::statistics(std::chrono::milliseconds deadline) {
  grpc::ClientContext context;
  context.set_deadline(after(deadline));
  v1::Statistics reply;
  const grpc::Status status = stub_->GetStatistics(&context, v1::StatisticsRequest(), &reply);
  if (!status.ok()) throw RpcError(status.error_code(), status.error_message());
  return reply;
}

v1::Price ShadowClient::estimate(const v1::EstimateRequest& request,
                                 std::chrono::milliseconds deadline) {
  grpc::ClientContext context;
  context.set_deadline(after(deadline));
  v1::Price reply;
  const grpc::Status status = stub_->Estimate(&context, request, &reply);
  if (!status.ok()) throw RpcError(status.error_code(), status.error_message());
  return reply;
}

bool ShadowClient::healthy(std::chrono::milliseconds deadline) {
  auto stub = grpc::health::v1::Health::NewStub(channel_);
  grpc::ClientContext context;
  context.set_deadline(after(deadline));
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(kServiceName);
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = stub->Check(&context, request, &response);
  return status.ok() && response.status() == grpc::health::v1::HealthCheckResponse::SERVING;
}

}  // namespace shadow::client
