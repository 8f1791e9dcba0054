#include "service/security.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <grpcpp/security/auth_metadata_processor.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include "wire/errors.hpp"

namespace shadow::service {
namespace {

constexpr const char* kTenantProperty = "shadow.tenant";
// Every method of grpc.health.v1.Health (Check, Watch), as HTTP/2's ":path" names it.
constexpr const char* kHealthPathPrefix = "/grpc.health.v1.Health/";

std::string read_file(const std::string& path, const char* flag) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw OptionError(std::string(flag) + ": cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// gRPC reports bad PEM files only when it first listens, as a failure to bind the port; they are
// parsed here first so that the start fails naming the flag and OpenSSL's reason.
using Bio = std::unique_ptr<BIO, decltype(&BIO_free)>;
using Certificate = std::unique_ptr<X509, decltype(&X509_free)>;
using Key = std::unique_ptr<EVP_PKEY, decltype(&EVP_PKEY_free)>;

Bio memory_bio(const std::string& pem) {
  return Bio(BIO_new_mem_buf(pem.data(), int(pem.size())), BIO_free);
}

// OpenSSL's reason for the last failure on this thread; clears its error queue.
std::string openssl_reason() {
  const char* reason = ERR_reason_error_string(ERR_peek_last_error());
  ERR_clear_error();
  return reason ? reason : "unknown error";
}

// Every certificate of a PEM file, in order (a chain: the leaf first); throws OptionError when
// there is none or one does not parse.
std::vector<Certificate> parse_certificates(const std::string& pem, const std::string& path,
                                            const char* flag) {
  ERR_clear_error();
  const Bio bio = memory_bio(pem);
  std::vector<Certificate> certificates;
  while (X509* c = PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr))
    certificates.emplace_back(c, X509_free);
  // The end of the data reads as "no start line"; anything else is a block that does not parse.
  const unsigned long error = ERR_peek_last_error();
  const bool at_end =
      ERR_GET_LIB(error) == ERR_LIB_PEM && ERR_GET_REASON(error) == PEM_R_NO_START_LINE;
  if (certificates.empty() && at_end)
    throw OptionError(std::string(flag) + ": " + path + " holds no PEM certificate");
  if (!at_end)
    throw OptionError(std::string(flag) + ": certificate " +
                      std::to_string(certificates.size() + 1) + " of " + path +
                      " does not parse: " + openssl_reason());
  ERR_clear_error();
  return certificates;
}

// Never asks for a passphrase (OpenSSL's default would prompt on the terminal): gRPC takes no
// encrypted key either.
int no_passphrase(char*, int, int, void*) {
  return -1;
}

void check_key_matches(const std::string& key_pem, const std::string& key_path,
                       const Certificate& leaf, const std::string& cert_path) {
  ERR_clear_error();
  const Bio bio = memory_bio(key_pem);
  const Key key(PEM_read_bio_PrivateKey(bio.get(), nullptr, no_passphrase, nullptr), EVP_PKEY_free);
  if (!key)
    throw OptionError("--tls-key: " + key_path +
                      " holds no unencrypted PEM private key: " + openssl_reason());
  if (X509_check_private_key(leaf.get(), key.get()) != 1)
    throw OptionError("--tls-key: " + key_path + " is not the key of the certificate in " +
                      "--tls-cert " + cert_path + ": " + openssl_reason());
  ERR_clear_error();
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
    // Health checks are open: probes (Kubernetes', a load balancer's) hold no token, and the
    // answer tells only whether the server serves. gRPC passes the call's ":path" here, the
    // method it routes the call to, so no other method can pass for one of these.
    const auto path = metadata.find(":path");
    if (path != metadata.end() && path->second.starts_with(kHealthPathPrefix))
      return grpc::Status::OK;
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
      throw OptionError("--auth-tokens: line " + std::to_string(number) +
                        ": expected 'TOKEN TENANT'");
    if (!tenants.emplace(token, tenant).second)
      throw OptionError("--auth-tokens: line " + std::to_string(number) +
                        ": the token is listed twice");
  }
  if (tenants.empty()) throw OptionError("--auth-tokens: the file lists no token");
  return tenants;
}

std::shared_ptr<grpc::ServerCredentials> make_server_credentials(const SecurityOptions& o) {
  const bool tls = !o.tls_cert.empty() || !o.tls_key.empty();
  if (tls && (o.tls_cert.empty() || o.tls_key.empty()))
    throw OptionError("--tls-cert and --tls-key go together");
  if (!tls && !o.tls_client_ca.empty())
    throw OptionError("--tls-client-ca needs --tls-cert and --tls-key");
  // gRPC runs an AuthMetadataProcessor only on SSL credentials, and a token sent in plaintext
  // is a token given away.
  if (!tls && !o.auth_tokens.empty())
    throw OptionError("--auth-tokens needs TLS (--tls-cert and --tls-key)");
  if (!tls) return grpc::InsecureServerCredentials();

  grpc::SslServerCredentialsOptions ssl;
  const std::string cert = read_file(o.tls_cert, "--tls-cert");
  const std::string key = read_file(o.tls_key, "--tls-key");
  check_key_matches(key, o.tls_key, parse_certificates(cert, o.tls_cert, "--tls-cert").front(),
                    o.tls_cert);
  ssl.pem_key_cert_pairs.push_back({key, cert});
  if (!o.tls_client_ca.empty()) {
    ssl.pem_root_certs = read_file(o.tls_client_ca, "--tls-client-ca");
    parse_certificates(ssl.pem_root_certs, o.tls_client_ca, "--tls-client-ca");
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
