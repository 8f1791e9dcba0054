// shadow-server's start-up output: what it is doing, and nothing from its libraries that lacks
// context. Two sources wrote such lines:
// - the OpenCL compiler: PoCL's clang prints "N warnings generated." straight to file
//   descriptor 2 for each program it builds (the warnings themselves are in the program's build
//   log), three context-free lines over the ~10 s of a first start;
// - gRPC's own log (gpr_log): a port that is taken printed a raw "E1128 ... chttp2_server.cc:1045]
//   UNKNOWN:No address added ..." line before the server's own message said the same.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace shadow::service {

// While alive, whatever the process writes to file descriptor 2 (stderr) goes to an anonymous
// temporary file instead. stop() (or the destructor) restores stderr and returns the text.
// Nothing else should write to stderr meanwhile: the server's own lines go before and after.
class StderrCapture {
 public:
  StderrCapture();
  ~StderrCapture();
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;

  // Restores stderr and returns what was written since construction ("" after the first call).
  std::string stop();
  // Writes `line` and a newline to the real stderr, past the capture (not while stop() runs).
  void say(const std::string& line) const;

 private:
  int saved_ = -1;  // the real stderr; -1 when capture could not start or has stopped
  int file_ = -1;
};

// While alive, says every `every` how many OpenCL programs this process has built so far
// ("shadow-server: still building (4 s): 12 OpenCL programs built so far"): a first start on a
// device compiles every kernel (12-25 s on PoCL here, the last part its kernels' first launches);
// a start from PoCL's cache is over before the first line.
class BuildProgress {
 public:
  explicit BuildProgress(std::function<void(const std::string&)> say,
                         std::chrono::milliseconds every = std::chrono::seconds(2));
  ~BuildProgress();  // stops; no line after it returns
  BuildProgress(const BuildProgress&) = delete;
  BuildProgress& operator=(const BuildProgress&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

// The lines of what the OpenCL compiler wrote to stderr while the engine built its programs, as
// the server prints them: the bare counts ("3 warnings generated.") dropped, every other line
// prefixed "shadow-server: OpenCL compiler: ".
std::vector<std::string> compiler_lines(std::string_view captured);

// Routes gRPC's log (gpr_log) through the server's voice: "shadow-server: gRPC error: MESSAGE
// (FILE:LINE)"; at GRPC_VERBOSITY's level, as before. Idempotent.
void route_grpc_log();

// While alive (one at a time), gRPC's log lines are kept instead of printed; lines() returns
// them. For a step whose failure the server reports itself (binding the port). Calls
// route_grpc_log().
class GrpcLogCapture {
 public:
  GrpcLogCapture();
  ~GrpcLogCapture();
  GrpcLogCapture(const GrpcLogCapture&) = delete;
  GrpcLogCapture& operator=(const GrpcLogCapture&) = delete;

  std::vector<std::string> lines() const;
  // Prints the kept lines as route_grpc_log() would have.
  void print() const;
};

// The OS's reason in a gRPC error text, e.g. "Address already in use" from its
// `os_error:"Address already in use"`; "" when it names none.
std::string os_error_in(std::string_view grpc_message);

}  // namespace shadow::service
