#include "shadow_client.hpp"

#include <fstream>
#include <new>
#include <sstream>

#include "grpc/health/v1/health.grpc.pb.h"
#include "wire/convert.hpp"
#include "wire/result_assembler.hpp"

namespace shadow::client {
namespace {

std::chrono::system_clock::time_point after(std::chrono::milliseconds deadline) {
  return std::chrono::system_clock::now() + deadline;
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

std::shared_ptr<grpc::Channel> ShadowClient::make_channel(const std::string& address,
                                                          const Credentials& credentials) {
  grpc::ChannelArguments args;
  // Chunks are 2 MiB; allow a server configured with bigger ones. Requests carry whole scenes.
  args.SetMaxReceiveMessageSize(kMaxReceiveBytes);
  args.SetMaxSendMessageSize(-1);
  return grpc::CreateCustomChannel(address, channel_credentials(credentials), args);
}

ShadowClient::ShadowClient(const std::string& address, const Credentials& credentials)
    : ShadowClient(make_channel(address, credentials)) {}

ShadowClient::ShadowClient(std::shared_ptr<grpc::Channel> channel)
    : channel_(std::move(channel)), stub_(v1::ShadowService::NewStub(channel_)) {}

RenderResult ShadowClient::render(const v1::RenderRequest& request,
                                  std::chrono::milliseconds deadline, const Progress& progress) {
  grpc::ClientContext context;
  context.set_deadline(after(deadline));
  std::unique_ptr<grpc::ClientReader<v1::RenderResponse>> reader = stub_->Render(&context, request);

  convert::ResultAssembler assembler;
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
    return assembler.finish();
  } catch (const convert::StreamError& e) {
    throw RpcError(grpc::StatusCode::DATA_LOSS, std::string("bad Render stream: ") + e.what());
  }
}

RenderResult ShadowClient::render(const RenderRequest& request,
                                  std::chrono::milliseconds deadline) {
  return render(convert::to_proto(request), deadline);
}

v1::Statistics ShadowClient::statistics(std::chrono::milliseconds deadline) {
  grpc::ClientContext context;
  context.set_deadline(after(deadline));
  v1::Statistics reply;
  const grpc::Status status = stub_->GetStatistics(&context, v1::StatisticsRequest(), &reply);
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
