// shadow-server: serves ShadowService, grpc.health.v1 and server reflection until SIGINT or
// SIGTERM. Prints "listening on ADDR" once it accepts calls (scripts wait for that line).
// Exit codes: 0 after SIGINT or SIGTERM; 2 for a bad command line or option value, named in the
// message; 1 when the server cannot start otherwise (no OpenCL device, the port taken).
#include <cerrno>
#include <climits>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_builder.h>
#include <CLI/CLI.hpp>

#include "service/server.hpp"

namespace {

// A reader may stall this long at most: past a day it is holding its reply's memory, not slow.
constexpr double kMaxStallSeconds = 86400;
// gRPC takes connection ages in milliseconds in an int (about 24.8 days).
constexpr double kMaxConnectionAgeSeconds = INT_MAX / 1000;

// A finite number in [low, high], or (low, high] when `low_open`. CLI11's own ranges let NaN
// through (every comparison with it is false), and 1e300 s overflows the milliseconds.
CLI::Validator finite_in(const char* unit, double low, bool low_open, double high = HUGE_VAL) {
  std::ostringstream range;
  range << std::setprecision(10);  // 2147483, not 2.14748e+06
  if (std::isinf(high))
    range << (low_open ? "> " : ">= ") << low;
  else
    range << "in " << (low_open ? "(" : "[") << low << ", " << high << "]";
  return CLI::Validator(
      [=, range = range.str()](std::string& text) -> std::string {
        double value = 0;
        if (CLI::detail::lexical_cast(text, value) && std::isfinite(value) &&
            (low_open ? value > low : value >= low) && value <= high)
          return "";
        return "must be a finite number of " + std::string(unit) + " " + range + ": got " + text;
      },
      range.str());
}

// A whole number >= `min`. CLI11 2.1 reads "-1" into an unsigned option as 2^64 - 1 (strtoull
// wraps it), and a number past 2^64 as 2^64 - 1 as well; it refuses other non-numbers itself.
CLI::Validator whole_number(unsigned long long min = 0) {
  const std::string range = ">= " + std::to_string(min);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        if (text.find('-') != std::string::npos)
          return "must be a whole number " + range + ": got " + text;
        errno = 0;
        char* end = nullptr;
        const unsigned long long value = std::strtoull(text.c_str(), &end, 0);
        if (errno == ERANGE) return "must be below 2^64: got " + text;
        if (*end == '\0' && value < min) return "must be a whole number " + range + ": got " + text;
        return "";
      },
      range);
}

// HOST:PORT, an IPv6 host in brackets ("[::1]:0"). gRPC would bind port 99999 as 34463 (its low
// 16 bits).
const CLI::Validator kListenAddress(
    [](std::string& text) -> std::string {
      const auto colon = text.rfind(':');
      const std::string host = colon == std::string::npos ? "" : text.substr(0, colon);
      const std::string port = colon == std::string::npos ? "" : text.substr(colon + 1);
      const bool bracketed = host.size() > 2 && host.front() == '[' && host.back() == ']';
      const bool host_ok = bracketed || (!host.empty() && host.find(':') == std::string::npos);
      const bool port_ok = !port.empty() && port.size() <= 5 &&
                           port.find_first_not_of("0123456789") == std::string::npos &&
                           std::stoi(port) <= 65535;
      if (host_ok && port_ok) return "";
      return "must be HOST:PORT with a port in 0..65535 (0: a free one; IPv6 as [::1]:0): got " +
             text;
    },
    "HOST:PORT");

std::chrono::milliseconds milliseconds(double seconds) {
  // Up: a positive number of seconds never becomes 0 ms, which means "never" or "at once".
  return std::chrono::milliseconds(int64_t(std::ceil(seconds * 1000)));
}

// A plaintext server that answers grpc.health.v1 and nothing else, for probes that cannot speak
// TLS (Kubernetes' built-in gRPC probe); the caller mirrors the main server's status on it.
std::unique_ptr<grpc::Server> start_health_server(const std::string& listen, std::string* address) {
  grpc::ServerBuilder builder;
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);  // a taken port fails the start
  int port = 0;
  builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), &port);
  // Its only services: the default health service and reflection, both enabled for the process
  // by ShadowServer.
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0)
    throw std::runtime_error("--health-listen: cannot listen on " + listen +
                             " (is another server using that port?)");
  *address = listen.substr(0, listen.rfind(':')) + ":" + std::to_string(port);
  grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService();
  health->SetServingStatus(shadow::service::kServiceName, true);
  health->SetServingStatus("", true);
  return server;
}

}  // namespace

int main(int argc, char** argv) {
  shadow::service::ServerOptions options;
  CLI::App app{"Shadow-texture service over gRPC (OpenCL engine)"};
  app.add_option("--listen", options.listen, "address to listen on (port 0 picks a free port)")
      ->capture_default_str()
      ->check(kListenAddress);
  app.add_option("--max-output-bytes", options.engine.max_output_bytes,
                 "limit on the bytes of all textures of one reply (RESOURCE_EXHAUSTED above)")
      ->capture_default_str()
      ->check(whole_number(1));
  app.add_option("--max-request-bytes", options.max_request_bytes,
                 "limit on the size of one request message (the inline scene)")
      ->capture_default_str()
      ->check(whole_number(1));
  app.add_option("--max-concurrent", options.engine.max_concurrent,
                 "requests rendering at once, each with a workspace of its own")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--max-queue", options.engine.max_queue,
                 "requests waiting for a workspace; past it RESOURCE_EXHAUSTED")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--memory-budget", options.engine.memory_budget,
                 "bytes of device buffers, waiting requests and replies being streamed together "
                 "(0: the device's global memory); past it RESOURCE_EXHAUSTED")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--max-request-cost", options.engine.max_request_cost_ms,
                 "estimated device milliseconds above which a request is refused "
                 "(RESOURCE_EXHAUSTED); 0 = no limit")
      ->capture_default_str()
      ->check(finite_in("milliseconds", 0, false));
  app.add_option("--idle-trim-delay", options.engine.idle_trim_delay_ms,
                 "ms the server must be idle, holding more than 256 MiB of scratch buffers, "
                 "before it gives them back (0: as soon as the last request ends)")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--tls-cert", options.security.tls_cert, "PEM certificate chain: serve TLS");
  app.add_option("--tls-key", options.security.tls_key, "PEM private key of --tls-cert");
  app.add_option("--tls-client-ca", options.security.tls_client_ca,
                 "PEM CA certificates: require client certificates they sign (mTLS)");
  app.add_option(
      "--auth-tokens", options.security.auth_tokens,
      "file of 'TOKEN TENANT' lines: require 'authorization: Bearer TOKEN' on every call "
      "but health checks (needs TLS)");
  std::string health_listen;
  app.add_option("--health-listen", health_listen,
                 "also answer grpc.health.v1, and nothing else, in plaintext on this address: "
                 "for probes that cannot speak TLS (Kubernetes' gRPC probe)")
      ->check(kListenAddress);
  app.add_option("--tenant-max-concurrent", options.tenant_max_concurrent,
                 "requests one tenant may have rendering or waiting (0: no limit); past it "
                 "RESOURCE_EXHAUSTED")
      ->capture_default_str()
      ->check(whole_number());
  std::string log_format = "text";
  app.add_option("--scene-cache-bytes", options.scene_cache.total_bytes,
                 "bytes of uploaded scenes kept for requests by scene id (least recently used "
                 "out first)")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--tenant-scene-cache-bytes", options.scene_cache.tenant_bytes,
                 "bytes of uploaded scenes kept per tenant (0: --scene-cache-bytes)")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--device-scene-bytes", options.engine.resident_scene_bytes,
                 "device memory for uploaded scenes kept between the requests that name them "
                 "(least recently used out first)")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--log-format", log_format, "one line per request on stderr: text | json | none")
      ->capture_default_str()
      ->check(CLI::IsMember({"text", "json", "none"}));
  double stall_seconds = 30;
  app.add_option("--stall-timeout", stall_seconds,
                 "seconds a client may read nothing of its reply before it is cancelled (at most "
                 "a day, 86400)")
      ->capture_default_str()
      ->check(finite_in("seconds", 0, true, kMaxStallSeconds));
  double connection_age = 0, connection_age_grace = 0;
  app.add_option("--max-connection-age", connection_age,
                 "seconds after which a client connection is closed (GOAWAY) so that clients "
                 "balancing over a DNS name re-resolve; 0: never; at most 2147483 (gRPC's limit)")
      ->capture_default_str()
      ->check(finite_in("seconds", 0, false, kMaxConnectionAgeSeconds));
  app.add_option("--max-connection-age-grace", connection_age_grace,
                 "seconds calls in flight on such a connection may still run; 0: to their end; "
                 "at most 2147483")
      ->capture_default_str()
      ->check(finite_in("seconds", 0, false, kMaxConnectionAgeSeconds));
  std::string calibration;
  app.add_option("--calibration", calibration,
                 "the quality goals' calibration table (CSV, as shadow-bench --calibration writes "
                 "it); default: the built-in data/calibration.csv");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help prints and exits 0. Every other refusal exits 2, whatever CLI11's own code for it
    // (104 for a value that does not convert, 105 for one a check refuses, ...).
    if (e.get_exit_code() == int(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << "shadow-server: " << e.what() << " (--help lists the options)\n";
    return 2;
  }
  if (!calibration.empty()) {
    try {
      options.engine.calibration =
          std::make_shared<const shadow::Calibration>(shadow::Calibration::load(calibration));
    } catch (const std::exception& e) {
      std::cerr << "shadow-server: --calibration " << e.what() << '\n';
      return 2;
    }
  }
  options.max_connection_age = milliseconds(connection_age);
  options.max_connection_age_grace = milliseconds(connection_age_grace);
  options.stall_timeout = milliseconds(stall_seconds);
  options.log_format = log_format == "json"   ? shadow::service::LogFormat::kJson
                       : log_format == "text" ? shadow::service::LogFormat::kText
                                              : shadow::service::LogFormat::kNone;

  // Block the stop signals in every thread (gRPC's and OpenCL's inherit this mask) and take
  // them synchronously below, where calling Shutdown() is safe.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  try {
    shadow::service::ShadowServer server(options);
    std::cerr << "shadow-server: engine on " << server.engine().device_name() << '\n';
    if (options.security.tls_cert.empty() && !shadow::service::is_loopback(options.listen))
      std::cerr << "shadow-server: warning: listening on " << options.listen
                << " without TLS: requests, scenes and textures cross the network in plaintext "
                   "(--tls-cert, --tls-key)\n";
    std::string health_address;
    const std::unique_ptr<grpc::Server> health_server =
        health_listen.empty() ? nullptr : start_health_server(health_listen, &health_address);
    std::cout << "listening on " << server.address() << std::endl;
    if (health_server) std::cout << "health checks on " << health_address << std::endl;

    int signal = 0;
    sigwait(&stop_signals, &signal);
    std::cerr << "shadow-server: " << (signal == SIGINT ? "SIGINT" : "SIGTERM")
              << ", shutting down\n";
    if (health_server) health_server->GetHealthCheckService()->Shutdown();  // NOT_SERVING
    server.shutdown();
    if (health_server) health_server->Shutdown(std::chrono::system_clock::now());
  } catch (const shadow::service::OptionError& e) {
    std::cerr << "shadow-server: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "shadow-server: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
