// TLS, mTLS and bearer tokens on the real server, with certificates made by openssl at test time
// (make_certs.sh): the right status for a missing client certificate, a wrong CA, a missing or
// unknown token, and plaintext; health checks need no token; tokens without TLS stop the start;
// per-tenant limits.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>

#include "grpc/health/v1/health.grpc.pb.h"
#include "service/server.hpp"
#include "shadow_client.hpp"
#include "test_scene.hpp"
#include "wire/errors.hpp"

namespace shadow::test {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

class SecurityTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("shadow-certs-" + std::to_string(getpid()));
    const std::string command = std::string("bash ") + SHADOW_MAKE_CERTS + " " + dir_.string();
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    std::ofstream(dir_ / "tokens") << "# token tenant\nsecret-a alice\nsecret-b bob\n";
    service::ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.security = {file("server.pem"), file("server.key"), file("ca.pem"), file("tokens")};
    server_ = std::make_unique<service::ShadowServer>(options);
  }
  static void TearDownTestSuite() {
    server_.reset();
    fs::remove_all(dir_);
  }
  static std::string file(const std::string& name) { return (dir_ / name).string(); }

  // The status a render gets with these credentials (OK when it renders).
  static grpc::StatusCode render_with(const client::Credentials& credentials,
                                      std::string* message = nullptr) {
    try {
      client::ShadowClient c(server_->address(), credentials);
      c.render(tiny_proto_request(), std::chrono::seconds(60));
      return grpc::StatusCode::OK;
    } catch (const client::RpcError& e) {
      if (message) *message = e.what();
      return e.code();
    }
  }
  static client::Credentials good() {
    return {file("ca.pem"), file("client.pem"), file("client.key"), "secret-a", ""};
  }

  static inline fs::path dir_;
  static inline std::unique_ptr<service::ShadowServer> server_;
};

TEST_F(SecurityTest, AClientWithCertificateAndTokenRenders) {
  EXPECT_EQ(render_with(good()), grpc::StatusCode::OK);
  client::Credentials bob = good();
  bob.token = "secret-b";
  EXPECT_EQ(render_with(bob), grpc::StatusCode::OK);
}

// Scenes are per tenant: another tenant's id is NOT_FOUND, as if never uploaded (it learns
// nothing), and its own upload of the same content is its own copy.
TEST_F(SecurityTest, EachTenantHasItsOwnScenes) {
  client::ShadowClient alice(server_->address(), good());
  const v1::RenderRequest inline_request = tiny_proto_request();
  const std::string id = alice.upload_scene(inline_request.scene());
  v1::RenderRequest request = inline_request;
  request.set_scene_id(id);
  EXPECT_NO_THROW(alice.render(request, std::chrono::seconds(60)));
  client::Credentials bob_credentials = good();
  bob_credentials.token = "secret-b";
  client::ShadowClient bob(server_->address(), bob_credentials);
  try {
    bob.render(request, std::chrono::seconds(60));
    ADD_FAILURE() << "bob rendered alice's scene";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::NOT_FOUND);
  }
  EXPECT_EQ(bob.upload_scene(inline_request.scene()), id);
  EXPECT_NO_THROW(bob.render(request, std::chrono::seconds(60)));
}

// Statistics are per tenant: each sees only its own calls.
TEST_F(SecurityTest, EachTenantSeesItsOwnStatistics) {
  client::Credentials carol = good();
  const auto before = [&] {
    client::ShadowClient c(server_->address(), carol);
    return c.statistics();
  };
  carol.token = "secret-c";  // carol's token is unknown: no statistics at all
  EXPECT_THROW(before(), client::RpcError);
  client::Credentials bob = good();
  bob.token = "secret-b";
  client::ShadowClient bob_client(server_->address(), bob);
  const uint64_t bob_before = bob_client.statistics().total().run_time().samples();
  bob_client.render(tiny_proto_request());
  const v1::Statistics s = bob_client.statistics();
  ASSERT_EQ(s.tenants_size(), 1);
  EXPECT_EQ(s.tenants(0).tenant(), "bob");
  EXPECT_EQ(s.total().tenant(), "bob");
  EXPECT_EQ(s.total().run_time().samples(), bob_before + 1);
}

TEST_F(SecurityTest, AMissingOrUnknownTokenIsUnauthenticated) {
  client::Credentials c = good();
  std::string message;
  c.token = "";
  EXPECT_EQ(render_with(c, &message), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_THAT(message, HasSubstr("missing token"));
  c.token = "secret-c";
  EXPECT_EQ(render_with(c, &message), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_THAT(message, HasSubstr("unknown token"));
}

// Health checks are open: a probe (Kubernetes', a load balancer's) holds no token, and the answer
// tells only whether the server serves. Every other call still needs a token.
TEST_F(SecurityTest, HealthChecksNeedNoTokenButEverythingElseDoes) {
  client::Credentials c = good();
  c.token = "";
  const auto channel = client::ShadowClient::make_channel(server_->address(), c);
  EXPECT_TRUE(client::ShadowClient(channel).healthy(std::chrono::seconds(30)));

  const auto health = grpc::health::v1::Health::NewStub(channel);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service::kServiceName);
  grpc::health::v1::HealthCheckResponse response;
  {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    const grpc::Status status = health->Check(&context, request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
  }
  {
    grpc::ClientContext context;  // Watch's first message is the status now
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    const auto watch = health->Watch(&context, request);
    ASSERT_TRUE(watch->Read(&response));
    EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
    context.TryCancel();
  }

  std::string message;
  EXPECT_EQ(render_with(c, &message), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_THAT(message, HasSubstr("missing token"));
  try {
    client::ShadowClient(channel).statistics();
    ADD_FAILURE() << "statistics without a token";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::UNAUTHENTICATED);
  }
}

// A failed TLS handshake never reaches a call: gRPC reports the connection as UNAVAILABLE.
TEST_F(SecurityTest, AMissingOrForeignClientCertificateIsRefusedAtTheHandshake) {
  client::Credentials c = good();
  c.tls_cert = c.tls_key = "";
  EXPECT_EQ(render_with(c), grpc::StatusCode::UNAVAILABLE);
  c = good();
  c.tls_cert = file("other_client.pem"), c.tls_key = file("other_client.key");
  EXPECT_EQ(render_with(c), grpc::StatusCode::UNAVAILABLE);
}

TEST_F(SecurityTest, AServerCertificateFromAnotherCaIsNotTrusted) {
  client::Credentials c = good();
  c.tls_ca = file("other_ca.pem");
  EXPECT_EQ(render_with(c), grpc::StatusCode::UNAVAILABLE);
}

TEST_F(SecurityTest, PlaintextGetsNoAnswer) {
  EXPECT_EQ(render_with({}), grpc::StatusCode::UNAVAILABLE);
}

TEST_F(SecurityTest, TokensWithoutTlsStopTheStart) {
  service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  options.security.auth_tokens = file("tokens");
  EXPECT_THROW(
      {
        try {
          service::ShadowServer server(options);
        } catch (const std::runtime_error& e) {
          EXPECT_THAT(e.what(), HasSubstr("--auth-tokens needs TLS"));
          throw;
        }
      },
      std::runtime_error);
}

TEST(TokenFile, LinesAreTokenAndTenant) {
  const auto tenants = service::parse_tokens("a alice\n\n  # comment\nb bob # trailing\n");
  EXPECT_EQ(tenants.size(), 2u);
  EXPECT_EQ(tenants.at("b"), "bob");
  EXPECT_THROW(service::parse_tokens("a alice\nb\n"), std::runtime_error);
  EXPECT_THROW(service::parse_tokens("a alice extra\n"), std::runtime_error);
  EXPECT_THROW(service::parse_tokens("a alice\na bob\n"), std::runtime_error);
  EXPECT_THROW(service::parse_tokens("# none\n"), std::runtime_error);
}

TEST(TenantLimiter, EachTenantHasItsOwnLimit) {
  service::TenantLimiter limiter(2);
  auto a1 = limiter.acquire("alice");
  auto a2 = limiter.acquire("alice");
  EXPECT_THROW(limiter.acquire("alice"), ResourceExhausted);
  auto b1 = limiter.acquire("bob");  // another tenant is not held up
  { auto moved = std::move(a2); }    // released
  auto a3 = limiter.acquire("alice");
  EXPECT_THROW(limiter.acquire("alice"), ResourceExhausted);
}

TEST(Listening, OnlyLoopbackCountsAsSafeForPlaintext) {
  EXPECT_TRUE(service::is_loopback("127.0.0.1:50051"));
  EXPECT_TRUE(service::is_loopback("localhost:1"));
  EXPECT_TRUE(service::is_loopback("[::1]:1"));
  EXPECT_FALSE(service::is_loopback("0.0.0.0:50051"));
  EXPECT_FALSE(service::is_loopback("[::]:50051"));
  EXPECT_FALSE(service::is_loopback("10.0.0.2:50051"));
}

}  // namespace
}  // namespace shadow::test
