// shadow-server: serves ShadowService, grpc.health.v1 and server reflection until SIGINT or
// SIGTERM. Prints "listening on ADDR" once it accepts calls (scripts wait for that line).
#include <csignal>
#include <cstdint>
#include <exception>
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "service/server.hpp"

int main(int argc, char** argv) {
  shadow::service::ServerOptions options;
  CLI::App app{"Shadow-texture service over gRPC (OpenCL engine)"};
  app.add_option("--listen", options.listen, "address to listen on (port 0 picks a free port)")
      ->capture_default_str();
  app.add_option("--max-output-bytes", options.engine.max_output_bytes,
                 "limit on the bytes of all textures of one reply (RESOURCE_EXHAUSTED above)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-request-bytes", options.max_request_bytes,
                 "limit on the size of one request message (the inline scene)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-concurrent", options.engine.max_concurrent,
                 "requests rendering at once, each with a workspace of its own")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--max-queue", options.engine.max_queue,
                 "requests waiting for a workspace; past it RESOURCE_EXHAUSTED")
      ->capture_default_str();
  app.add_option("--memory-budget", options.engine.memory_budget,
                 "bytes of device buffers, waiting requests and replies being streamed together "
                 "(0: the device's global memory); past it RESOURCE_EXHAUSTED")
      ->capture_default_str();
  app.add_option("--max-request-cost", options.engine.max_request_cost_ms,
                 "estimated device milliseconds above which a request is refused "
                 "(RESOURCE_EXHAUSTED); 0 = no limit")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--idle-trim-delay", options.engine.idle_trim_delay_ms,
                 "ms the server must be idle, holding more than 256 MiB of scratch buffers, "
                 "before it gives them back (0: as soon as the last request ends)")
      ->capture_default_str();
  app.add_option("--tls-cert", options.security.tls_cert, "PEM certificate chain: serve TLS");
  app.add_option("--tls-key", options.security.tls_key, "PEM private key of --tls-cert");
  app.add_option("--tls-client-ca", options.security.tls_client_ca,
                 "PEM CA certificates: require client certificates they sign (mTLS)");
  app.add_option("--auth-tokens", options.security.auth_tokens,
                 "file of 'TOKEN TENANT' lines: require 'authorization: Bearer TOKEN' (needs TLS)");
  app.add_option("--tenant-max-concurrent", options.tenant_max_concurrent,
                 "requests one tenant may have rendering or waiting (0: no limit); past it "
                 "RESOURCE_EXHAUSTED")
      ->capture_default_str();
  std::string log_format = "text";
  app.add_option("--scene-cache-bytes", options.scene_cache.total_bytes,
                 "bytes of uploaded scenes kept for requests by scene id (least recently used "
                 "out first)")
      ->capture_default_str();
  app.add_option("--tenant-scene-cache-bytes", options.scene_cache.tenant_bytes,
                 "bytes of uploaded scenes kept per tenant (0: --scene-cache-bytes)")
      ->capture_default_str();
  app.add_option("--device-scene-bytes", options.engine.resident_scene_bytes,
                 "device memory for uploaded scenes kept between the requests that name them "
                 "(least recently used out first)")
      ->capture_default_str();
  app.add_option("--log-format", log_format, "one line per request on stderr: text | json | none")
      ->capture_default_str()
      ->check(CLI::IsMember({"text", "json", "none"}));
  double stall_seconds = 30;
  app.add_option("--stall-timeout", stall_seconds,
                 "seconds a client may read nothing of its reply before it is cancelled")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  double connection_age = 0, connection_age_grace = 0;
  app.add_option("--max-connection-age", connection_age,
                 "seconds after which a client connection is closed (GOAWAY) so that clients "
                 "balancing over a DNS name re-resolve; 0: never")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-connection-age-grace", connection_age_grace,
                 "seconds calls in flight on such a connection may still run; 0: to their end")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  std::string calibration;
  app.add_option("--calibration", calibration,
                 "the quality goals' calibration table (CSV, as shadow-bench --calibration writes "
                 "it); default: the built-in data/calibration.csv");
  CLI11_PARSE(app, argc, argv);
  if (!calibration.empty()) {
    try {
      options.engine.calibration =
          std::make_shared<const shadow::Calibration>(shadow::Calibration::load(calibration));
    } catch (const std::exception& e) {
      std::cerr << "shadow-server: --calibration " << e.what() << '\n';
      return 2;
    }
  }
  options.max_connection_age = std::chrono::milliseconds(int64_t(connection_age * 1000));
  options.max_connection_age_grace =
      std::chrono::milliseconds(int64_t(connection_age_grace * 1000));
  options.stall_timeout = std::chrono::milliseconds(int64_t(stall_seconds * 1000));
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
    std::cout << "listening on " << server.address() << std::endl;

    int signal = 0;
    sigwait(&stop_signals, &signal);
    std::cerr << "shadow-server: " << (signal == SIGINT ? "SIGINT" : "SIGTERM")
              << ", shutting down\n";
    server.shutdown();
  } catch (const std::exception& e) {
    std::cerr << "shadow-server: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
