#include "service/start_up.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <mutex>
#include <regex>

#include <grpc/support/log.h>

#include "engine/cl/program_cache.hpp"

namespace shadow::service {

StderrCapture::StderrCapture() {
  std::fflush(stderr);
  std::FILE* file = std::tmpfile();
  if (!file) return;  // no temporary file: stderr stays as it is
  file_ = dup(fileno(file));
  std::fclose(file);  // the dup keeps the (already unlinked) file open
  saved_ = file_ < 0 ? -1 : dup(STDERR_FILENO);
  if (saved_ < 0 || dup2(file_, STDERR_FILENO) < 0) {
    if (saved_ >= 0) close(saved_);
    saved_ = -1;
  }
}

StderrCapture::~StderrCapture() {
  stop();
  if (file_ >= 0) close(file_);
}

void StderrCapture::say(const std::string& line) const {
  const std::string text = line + "\n";
  const int fd = saved_ >= 0 ? saved_ : STDERR_FILENO;
  if (write(fd, text.data(), text.size()) < 0) {
  }  // nowhere to say that it could not be said
}

BuildProgress::BuildProgress(std::function<void(const std::string&)> say,
                             std::chrono::milliseconds every) {
  const auto start = std::chrono::steady_clock::now();
  thread_ = std::thread([this, say = std::move(say), every, start] {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, every, [&] { return stop_; })) {
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      char line[128];
      std::snprintf(line, sizeof line,
                    "shadow-server: still building (%.0f s): %zu OpenCL programs built so far",
                    seconds, shadow::cl::ProgramCache::built_in_process().size());
      say(line);
    }
  });
}

BuildProgress::~BuildProgress() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

std::string StderrCapture::stop() {
  if (saved_ < 0) return "";
  std::fflush(stderr);
  dup2(saved_, STDERR_FILENO);
  close(saved_);
  saved_ = -1;
  std::string text;
  char buffer[4096];
  for (off_t at = 0;;) {
    const ssize_t n = pread(file_, buffer, sizeof buffer, at);
    if (n <= 0) break;
    text.append(buffer, size_t(n));
    at += n;
  }
  return text;
}

std::vector<std::string> compiler_lines(std::string_view captured) {
  static const std::regex count(
      R"(\s*\d+ (warnings?|errors?)( and \d+ (warnings?|errors?))? generated\.\s*)");
  std::vector<std::string> lines;
  size_t at = 0;
  while (at < captured.size()) {
    size_t end = captured.find('\n', at);
    if (end == std::string_view::npos) end = captured.size();
    const std::string line(captured.substr(at, end - at));
    at = end + 1;
    if (line.find_first_not_of(" \t\r") == std::string::npos || std::regex_match(line, count))
      continue;
    lines.push_back("shadow-server: OpenCL compiler: " + line);
  }
  return lines;
}

namespace {

struct LogLine {
  gpr_log_severity severity;
  std::string file;
  int line;
  std::string message;
};

std::mutex log_mutex;
std::vector<LogLine>* kept = nullptr;  // while a GrpcLogCapture is alive

std::string format(const LogLine& l) {
  const char* severity = l.severity == GPR_LOG_SEVERITY_ERROR  ? "error"
                         : l.severity == GPR_LOG_SEVERITY_INFO ? "info"
                                                               : "debug";
  const size_t slash = l.file.rfind('/');
  return "shadow-server: gRPC " + std::string(severity) + ": " + l.message + " (" +
         (slash == std::string::npos ? l.file : l.file.substr(slash + 1)) + ":" +
         std::to_string(l.line) + ")";
}

void log_function(gpr_log_func_args* args) {
  LogLine l{args->severity, args->file ? args->file : "", args->line,
            args->message ? args->message : ""};
  {
    std::lock_guard<std::mutex> lock(log_mutex);
    if (kept) {
      kept->push_back(std::move(l));
      return;
    }
  }
  std::fprintf(stderr, "%s\n", format(l).c_str());
}

}  // namespace

void route_grpc_log() {
  static std::once_flag once;
  std::call_once(once, [] { gpr_set_log_function(log_function); });
}

GrpcLogCapture::GrpcLogCapture() {
  route_grpc_log();
  std::lock_guard<std::mutex> lock(log_mutex);
  kept = new std::vector<LogLine>();
}

GrpcLogCapture::~GrpcLogCapture() {
  std::lock_guard<std::mutex> lock(log_mutex);
  delete kept;
  kept = nullptr;
}

std::vector<std::string> GrpcLogCapture::lines() const {
  std::lock_guard<std::mutex> lock(log_mutex);
  std::vector<std::string> out;
  for (const LogLine& l : *kept) out.push_back(l.message);
  return out;
}

void GrpcLogCapture::print() const {
  std::lock_guard<std::mutex> lock(log_mutex);
  for (const LogLine& l : *kept) std::fprintf(stderr, "%s\n", format(l).c_str());
}

std::string os_error_in(std::string_view grpc_message) {
  constexpr std::string_view kKey = "os_error:\"";
  const size_t at = grpc_message.find(kKey);
  if (at == std::string_view::npos) return "";
  const size_t from = at + kKey.size(), to = grpc_message.find('"', from);
  return to == std::string_view::npos ? "" : std::string(grpc_message.substr(from, to - from));
}

}  // namespace shadow::service
