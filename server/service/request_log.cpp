#include "service/request_log.hpp"

#include <cstdio>

#include "wire/status_names.hpp"

namespace shadow::service {
namespace {

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\', out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\u%04x", c);
      out += escape;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string ms(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", v);
  return text;
}

std::string joined(const std::vector<std::string>& items, const char* separator) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : separator) + item;
  return out;
}

}  // namespace

std::string format_log_line(const LogLine& l, LogFormat format) {
  const std::string code = status_code_name(l.code);
  if (format == LogFormat::kJson) {
    std::vector<std::string> products;
    for (const std::string& p : l.products) products.push_back(json_string(p));
    return "{\"event\":" + json_string(l.event) + ",\"tenant\":" + json_string(l.tenant) +
           ",\"peer\":" + json_string(l.peer) + ",\"products\":[" + joined(products, ",") +
           "],\"status\":" + json_string(code) + ",\"message\":" + json_string(l.message) +
           ",\"queue_ms\":" + ms(l.queue_ms) + ",\"run_ms\":" + ms(l.run_ms) +
           ",\"total_ms\":" + ms(l.total_ms) +
           ",\"request_bytes\":" + std::to_string(l.request_bytes) +
           ",\"reply_bytes\":" + std::to_string(l.reply_bytes) +
           ",\"previous_attempts\":" + std::to_string(l.previous_attempts) +
           ",\"frames\":" + std::to_string(l.frames) + ",\"scene_id\":" + json_string(l.scene_id) +
           "}";
  }
  std::string line =
      l.event + " tenant=" + (l.tenant.empty() ? "-" : l.tenant) + " peer=" + l.peer +
      " products=" + (l.products.empty() ? "-" : joined(l.products, ",")) + " status=" + code +
      " queue_ms=" + ms(l.queue_ms) + " run_ms=" + ms(l.run_ms) + " total_ms=" + ms(l.total_ms) +
      " request_bytes=" + std::to_string(l.request_bytes) +
      " reply_bytes=" + std::to_string(l.reply_bytes);
  if (l.previous_attempts > 0) line += " previous_attempts=" + std::to_string(l.previous_attempts);
  if (l.frames > 0) line += " frames=" + std::to_string(l.frames);
  if (!l.scene_id.empty()) line += " scene_id=" + l.scene_id;
  if (!l.message.empty()) line += " message=" + json_string(l.message);
  return line;
}

void RequestLog::write(const LogLine& line) {
  if (format_ == LogFormat::kNone) return;
  const std::string text = format_log_line(line, format_) + "\n";
  std::lock_guard<std::mutex> lock(mutex_);
  std::fwrite(text.data(), 1, text.size(), stderr);
  std::fflush(stderr);
}

}  // namespace shadow::service
