#include "service/security.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <grpcpp/security/auth_metadata_processor.h>

#include "wire/errors.hpp"

namespace shadow::service {
namespace {

constexpr const char* kTenantProperty = "shadow.tenant";

std::string read_file(const std::string& path, const char* flag) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(std::string(flag) + ": cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Checks "authorization: Bearer TOKEN" against the token file; the call's peer identity becomes
// the token's tenant. gRPC calls it for every call, before the handler, on TLS connections only.
class TokenProcessor final : public grpc::AuthMetadataProcessor {
 public:
  explicit TokenProcessor(std::map<std::string, std::string> tenants)
      : tenants_(std::move(tenants)) {}

  bool IsBlocking() const override { return false; }  // a map lookup

  grpc::Status Process(const InputMetadata& metadata, grpc::AuthContext* context,
                       OutputMetadata* consumed, OutputMetadata*) override {
    const auto header = metadata.find("authorization");
    if (header == metadata.end())
      return {grpc::StatusCode::UNAUTHENTICATED,
              "missing token: send 'authorization: Bearer TOKEN' (shadowctl --token)"};
    const std::string value(header->second.data(), header->second.size());
    const std::string prefix = "Bearer ";
    const auto tenant =
        value.rfind(prefix, 0) == 0 ? tenants_.find(value.substr(prefix.size())) : tenants_.end();
    if (tenant == tenants_.end()) return {grpc::StatusCode::UNAUTHENTICATED, "unknown token"};
    context->AddProperty(kTenantProperty, tenant->second);
    context->SetPeerIdentityPropertyName(kTenantProperty);
    consumed->insert({"authorization", value});
    return grpc::Status::OK;
  }

 private:
  const std::map<std::string, std::string> tenants_;
};

}  // namespace

std::map<std::string, std::string> parse_tokens(const std::string& text) {
  std::map<std::string, std::string> tenants;
  std::istringstream lines(text);
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number) {
    line = line.substr(0, line.find('#'));
    std::istringstream words(line);
    std::string token, tenant, extra;
    if (!(words >> token)) continue;  // blank or comment
    if (!(words >> tenant) || (words >> extra))
      throw std::runtime_error("--auth-tokens: line " + std::to_string(number) +
                               ": expected 'TOKEN TENANT'");
    if (!tenants.emplace(token, tenant).second)
      throw std::runtime_error("--auth-tokens: line " + std::to_string(number) +
                               ": the token is listed twice");
  }
  if (tenants.empty()) throw std::runtime_error("--auth-tokens: the file lists no token");
  return tenants;
}

std::shared_ptr<grpc::ServerCredentials> make_server_credentials(const SecurityOptions& o) {
  const bool tls = !o.tls_cert.empty() || !o.tls_key.empty();
  if (tls && (o.tls_cert.empty() || o.tls_key.empty()))
    throw std::runtime_error("--tls-cert and --tls-key go together");
  if (!tls && !o.tls_client_ca.empty())
    throw std::runtime_error("--tls-client-ca needs --tls-cert and --tls-key");
  // gRPC runs an AuthMetadataProcessor only on SSL credentials, and a token sent in plaintext
  // is a token given away.
  if (!tls && !o.auth_tokens.empty())
    throw std::runtime_error("--auth-tokens needs TLS (--tls-cert and --tls-key)");
  if (!tls) return grpc::InsecureServerCredentials();

  grpc::SslServerCredentialsOptions ssl;
  ssl.pem_key_cert_pairs.push_back(
      {read_file(o.tls_key, "--tls-key"), read_file(o.tls_cert, "--tls-cert")});
  if (!o.tls_client_ca.empty()) {
    ssl.pem_root_certs = read_file(o.tls_client_ca, "--tls-client-ca");
    ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  std::shared_ptr<grpc::ServerCredentials> credentials = grpc::SslServerCredentials(ssl);
  if (!o.auth_tokens.empty())
    credentials->SetAuthMetadataProcessor(
        std::make_shared<TokenProcessor>(parse_tokens(read_file(o.auth_tokens, "--auth-tokens"))));
  return credentials;
}

bool is_loopback(const std::string& listen) {
  const std::string host = listen.substr(0, listen.rfind(':'));
  return host.rfind("127.", 0) == 0 || host == "localhost" || host == "[::1]";
}

std::string tenant_of(const grpc::ServerContext& context) {
  const std::shared_ptr<const grpc::AuthContext> auth = context.auth_context();
  if (!auth) return "";
  const std::vector<grpc::string_ref> identity = auth->GetPeerIdentity();
  if (identity.empty() || auth->GetPeerIdentityPropertyName() != kTenantProperty) return "";
  return std::string(identity.front().data(), identity.front().size());
}

TenantLimiter::Slot TenantLimiter::acquire(const std::string& tenant) {
  std::lock_guard<std::mutex> lock(mutex_);
  unsigned& n = in_flight_[tenant];
  if (limit_ != 0 && n >= limit_)
    throw ResourceExhausted("tenant", "tenant '" + tenant + "' already has " + std::to_string(n) +
                                          " requests rendering or waiting, its limit "
                                          "(--tenant-max-concurrent)");
  ++n;
  return Slot(this, tenant);
}

TenantLimiter::Slot::~Slot() {
  if (!owner_) return;
  std::lock_guard<std::mutex> lock(owner_->mutex_);
  if (--owner_->in_flight_[tenant_] == 0) owner_->in_flight_.erase(tenant_);
}

}  // namespace shadow::service
