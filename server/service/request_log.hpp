// One line per Render call on stderr, as text or JSON (--log-format): tenant, products, status,
// timings and sizes, for log collectors and people alike.
#pragma once

#include <mutex>
#include <string>
#include <vector>

#include <grpcpp/support/status.h>

namespace shadow::service {

enum class LogFormat { kNone, kText, kJson };

struct LogLine {
  std::string event = "render";  // the call: "render", "sequence" or "upload"
  std::string tenant;
  std::string peer;                   // the client's address, as gRPC gives it
  std::vector<std::string> products;  // shadowctl's names; empty when the request did not decode
  grpc::StatusCode code = grpc::StatusCode::OK;
  std::string message;  // the status message ("" for OK)
  double queue_ms = 0, run_ms = 0, total_ms = 0;
  uint64_t request_bytes = 0, reply_bytes = 0;
  // gRPC's grpc-previous-rpc-attempts: how often the client's retry policy tried this call
  // before (on this replica or another); 0 for a first attempt.
  unsigned previous_attempts = 0;
  uint32_t frames = 0;   // sequence: frames sent
  std::string scene_id;  // by-id requests and uploads
};

std::string format_log_line(const LogLine& line, LogFormat format);

class RequestLog {
 public:
  explicit RequestLog(LogFormat format) : format_(format) {}
  // Writes the line, whole, to stderr (nothing for kNone).
  void write(const LogLine& line);

 private:
  LogFormat format_;
  std::mutex mutex_;
};

}  // namespace shadow::service
