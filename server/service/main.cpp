// shadow-server: serves ShadowService, grpc.health.v1 and server reflection until SIGINT or
// SIGTERM. Prints "listening on ADDR" once it accepts calls (scripts wait for that line).
// Exit codes: 0 after SIGINT or SIGTERM; 2 for a bad command line or option value, named in the
// message (a --device or $SHADOW_DEVICE that names no device among them); 1 when the server
// cannot start otherwise (no OpenCL device at all, the port taken).

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "engine/cl/program_cache.hpp"
#include "service/health_server.hpp"
#include "service/option_checks.hpp"
#include "service/server.hpp"
#include "service/start_up.hpp"

using shadow::service::compiler_lines;
using shadow::service::finite_in;
using shadow::service::kListenAddress;
using shadow::service::kMaxConnectionAgeSeconds;
using shadow::service::kMaxStallSeconds;
using shadow::service::milliseconds;
using shadow::service::route_grpc_log;
using shadow::service::start_health_server;
using shadow::service::StderrCapture;
using shadow::service::whole_number;

namespace {

// --list-devices: 0 when the SPEC (or the default) picks a device, 2 when it names none, 1 when
// there is no device at all.
int print_devices(const std::string& flag) {
  namespace cl = shadow::cl;
  try {
    const cl::Inventory inventory = cl::enumerate_devices();
    if (inventory.devices.empty()) {
      std::cout << cl::format_device_list(inventory.platforms, inventory.devices, std::nullopt);
      std::cerr << "shadow-server: no OpenCL device on any platform\n";
      return 1;
    }
    std::optional<size_t> chosen;
    std::string refusal;
    try {
      chosen = cl::choose_device(inventory.devices, cl::resolve_device_spec(flag));
    } catch (const cl::DeviceChoiceError& e) {
      refusal = e.what();
    }
    std::cout << cl::format_device_list(inventory.platforms, inventory.devices, chosen);
    if (refusal.empty()) return 0;
    std::cerr << "shadow-server: " << refusal << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "shadow-server: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  shadow::service::tune_allocator();
  // gRPC's own log lines speak in the server's voice ("shadow-server: gRPC error: ...").
  route_grpc_log();
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
                 "bytes of device buffers, waiting requests, uploads and replies being streamed "
                 "together (0: the device's global memory); a request waits until its buffers "
                 "fit, and what can never fit is RESOURCE_EXHAUSTED")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--max-request-cost", options.engine.max_request_cost_ms,
                 "estimated device milliseconds above which a request is refused "
                 "(RESOURCE_EXHAUSTED); 0 = no limit")
      ->capture_default_str()
      ->check(finite_in("milliseconds", 0, false));
  double sequence_minutes = options.engine.max_sequence_cost_ms / 60e3;
  app.add_option("--max-sequence-cost", sequence_minutes,
                 "estimated device minutes above which a RenderSequence, all its frames "
                 "together, is refused before any frame runs (RESOURCE_EXHAUSTED naming "
                 "max_sequence_cost); 0 = no limit")
      ->capture_default_str()
      ->check(finite_in("minutes", 0, false));
  std::vector<std::string> weights;
  app.add_option("--tenant-weight", weights,
                 "TENANT=W (repeatable): the tenant's weight in the device's fair share, W > 0; "
                 "a weight-2 tenant gets twice the device time of a weight-1 one when both "
                 "wait (others weigh 1)")
      ->check(shadow::service::kTenantWeight);
  double shutdown_grace =
      std::chrono::duration<double>(shadow::service::ShadowServer::kShutdownGrace).count();
  app.add_option("--shutdown-grace", shutdown_grace,
                 "seconds that calls in flight may still run after SIGTERM or SIGINT (health "
                 "NOT_SERVING and new calls UNAVAILABLE meanwhile); what still renders at its "
                 "end stops with UNAVAILABLE, which clients resume elsewhere. Keep it below "
                 "Kubernetes' terminationGracePeriodSeconds (30 s)")
      ->capture_default_str()
      ->check(finite_in("seconds", 0, false, kMaxStallSeconds));
  app.add_option("--overtake-max-cost", options.engine.overtake_max_ms,
                 "while the first request in line waits for memory, requests estimated at most "
                 "this many device ms whose buffers fit go first (0: strictly in order)")
      ->capture_default_str()
      ->check(finite_in("milliseconds", 0, false));
  app.add_option("--overtake-window", options.engine.overtake_window_ms,
                 "ms of the first in line's wait for memory during which such requests may go "
                 "first; after it, first come first served until it starts")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--idle-trim-delay", options.engine.idle_trim_delay_ms,
                 "ms the server must be idle, holding more than 256 MiB of scratch buffers, "
                 "before it gives them back (0: as soon as the last request ends)")
      ->capture_default_str()
      ->check(whole_number());
  app.add_option("--tls-cert", options.security.tls_cert, "PEM certificate chain: serve TLS")
      ->default_str("none: plaintext");
  app.add_option("--tls-key", options.security.tls_key, "PEM private key of --tls-cert");
  app.add_option("--tls-client-ca", options.security.tls_client_ca,
                 "PEM CA certificates: require client certificates they sign (mTLS)")
      ->default_str("none: no client certificates");
  app.add_option(
         "--auth-tokens", options.security.auth_tokens,
         "file of 'TOKEN TENANT' lines: require 'authorization: Bearer TOKEN' on every call "
         "but health checks (needs TLS)")
      ->default_str("none: no token asked");
  std::string health_listen;
  app.add_option("--health-listen", health_listen,
                 "also answer grpc.health.v1, and nothing else, in plaintext on this address: "
                 "for probes that cannot speak TLS (Kubernetes' gRPC probe)")
      ->default_str("none: health on --listen only")
      ->check(kListenAddress);
  app.add_option("--tenant-max-concurrent", options.tenant_max_concurrent,
                 "requests and uploads one tenant may have in flight (0: no limit); past it "
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
                 "seconds a client may read nothing of its reply, or send nothing of its upload, "
                 "before it is cancelled (at most a day, 86400)")
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
  app.add_option("--device", options.engine.device,
                 "the OpenCL device: P:D (platform:device, as --list-devices numbers them) or part "
                 "of a platform's name or vendor or of a device's name, any case (nvidia, pocl)")
      ->default_str("$SHADOW_DEVICE, else the first GPU, else the first CPU device");
  app.add_option("--kernel-profile", options.engine.kernel_profile,
                 "the kernels' shape: cpu (a work-item per strip or tile), gpu (a work-item per "
                 "pixel, in work-groups) or auto (by the device's type)")
      ->default_str("$SHADOW_KERNEL_PROFILE, else auto")
      ->check(CLI::IsMember({"cpu", "gpu", "auto"}));
  bool list_devices = false;
  app.add_flag("--list-devices", list_devices,
               "print every OpenCL platform and device (type, compute units, memory, OpenCL C "
               "version) and the one --device picks, then exit");
  std::string calibration;
  app.add_option("--calibration", calibration,
                 "the quality goals' calibration table (CSV, as shadow-bench --calibration writes "
                 "it)")
      ->default_str("the built-in data/calibration.csv");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help prints and exits 0. Every other refusal exits 2, whatever CLI11's own code for it
    // (104 for a value that does not convert, 105 for one a check refuses, ...).
    if (e.get_exit_code() == int(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << "shadow-server: " << e.what() << " (--help lists the options)\n";
    return 2;
  }
  if (list_devices) return print_devices(options.engine.device);
  if (!calibration.empty()) {
    try {
      options.engine.calibration =
          std::make_shared<const shadow::Calibration>(shadow::Calibration::load(calibration));
    } catch (const std::exception& e) {
      std::cerr << "shadow-server: --calibration " << e.what() << '\n';
      return 2;
    }
  }
  options.engine.max_sequence_cost_ms = sequence_minutes * 60e3;
  for (const std::string& w : weights) {
    const size_t eq = w.rfind('=');
    options.engine.client_weights[w.substr(0, eq)] = std::stod(w.substr(eq + 1));
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
    // The engine compiles every kernel before it serves: seconds from PoCL's cache, longer on a
    // first start. Say so, and keep the OpenCL compiler's bare "N warnings generated." lines
    // (printed to stderr per program; the warnings are in the build logs) out of the output.
    std::cerr << "shadow-server: building the engine's OpenCL programs (a first start on a device "
                 "takes a while; PoCL caches them for the next)...\n";
    const auto building = std::chrono::steady_clock::now();
    std::unique_ptr<shadow::service::ShadowServer> started;
    {
      // POCL_DEBUG asks for PoCL's own output as it happens: leave stderr alone then.
      std::optional<StderrCapture> compiler;
      if (!std::getenv("POCL_DEBUG")) compiler.emplace();
      try {
        // Says how far the build is while it lasts; stops before the capture does.
        const shadow::service::BuildProgress progress([&](const std::string& line) {
          if (compiler)
            compiler->say(line);
          else
            std::cerr << line << '\n';
        });
        started = std::make_unique<shadow::service::ShadowServer>(options);
      } catch (...) {
        if (compiler) std::cerr << compiler->stop();  // all of it: it may say why
        throw;
      }
      if (compiler)
        for (const std::string& line : compiler_lines(compiler->stop())) std::cerr << line << '\n';
    }
    shadow::service::ShadowServer& server = *started;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - building).count();
    char built[96];
    std::snprintf(built, sizeof built, "%zu OpenCL programs built in %.1f s",
                  shadow::cl::ProgramCache::built_in_process().size(), seconds);
    std::cerr << "shadow-server: engine on " << shadow::cl::describe(server.engine().device())
              << ", " << shadow::cl::shape_name(server.engine().profile().shape)
              << " kernel profile; " << built << "\n";
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
    server.shutdown(milliseconds(shutdown_grace));
    if (health_server) health_server->Shutdown(std::chrono::system_clock::now());
    std::cerr << "shadow-server: drained, exiting\n";
  } catch (const shadow::cl::DeviceChoiceError& e) {
    std::cerr << "shadow-server: " << e.what() << '\n';
    return 2;
  } catch (const shadow::service::OptionError& e) {
    std::cerr << "shadow-server: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "shadow-server: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
