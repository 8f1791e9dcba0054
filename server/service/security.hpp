// Transport security and tenants: TLS (optionally mutual) from PEM files, bearer tokens mapped
// to tenants by an AuthMetadataProcessor, and a cap on each tenant's requests in flight.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_context.h>

namespace shadow::service {

struct SecurityOptions {
  std::string tls_cert, tls_key;  // PEM files; both or neither
  std::string tls_client_ca;      // PEM file: require client certificates signed by it (mTLS)
  std::string auth_tokens;        // file of "token tenant" lines; needs TLS
};

// A start-up option whose value cannot work, with the flag named in the message: the operator's
// mistake (shadow-server exits 2), not the machine's (no device, a port taken: exit 1).
struct OptionError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The credentials to listen with. Throws OptionError for unreadable files, a certificate chain,
// key or client CA file that does not parse, a key that is not the certificate's, a key without
// a certificate, client CAs or tokens without TLS, or a malformed token file. With tokens, calls
// to grpc.health.v1.Health need none, so that probes which hold no token can check the server.
std::shared_ptr<grpc::ServerCredentials> make_server_credentials(const SecurityOptions& options);

// Whether `listen` ("host:port") is a loopback address, where plaintext is safe.
bool is_loopback(const std::string& listen);

// The tenant a call was authenticated as ("" without --auth-tokens).
std::string tenant_of(const grpc::ServerContext& context);

// "token tenant" lines ('#' starts a comment); throws OptionError naming the line.
std::map<std::string, std::string> parse_tokens(const std::string& text);

// At most `limit` requests per tenant rendering or waiting at once (0: no limit).
class TenantLimiter {
 public:
  explicit TenantLimiter(unsigned limit) : limit_(limit) {}

  class Slot {
   public:
    Slot(Slot&& other) noexcept : owner_(other.owner_), tenant_(std::move(other.tenant_)) {
      other.owner_ = nullptr;
    }
    ~Slot();

   private:
    friend class TenantLimiter;
    Slot(TenantLimiter* owner, std::string tenant) : owner_(owner), tenant_(std::move(tenant)) {}
    TenantLimiter* owner_;
    std::string tenant_;
  };

  // Throws ResourceExhausted when the tenant already has `limit` requests in flight.
  Slot acquire(const std::string& tenant);

 private:
  unsigned limit_;
  std::mutex mutex_;
  std::map<std::string, unsigned> in_flight_;
};

}  // namespace shadow::service
