#include "service/option_checks.hpp"

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <string>

namespace shadow::service {

CLI::Validator finite_in(const char* unit, double low, bool low_open, double high) {
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

CLI::Validator whole_number(unsigned long long min) {
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

const CLI::Validator kTenantWeight(
    [](std::string& text) -> std::string {
      const auto eq = text.rfind('=');
      if (eq == std::string::npos || eq == 0)
        return "must be TENANT=WEIGHT (a tenant of --auth-tokens, a weight > 0): got " + text;
      const std::string weight = text.substr(eq + 1);
      char* end = nullptr;
      const double w = std::strtod(weight.c_str(), &end);
      if (weight.empty() || *end != '\0' || !std::isfinite(w) || w <= 0 || w > 1e6)
        return "must be TENANT=WEIGHT with a finite weight in (0, 1e6]: got " + text;
      return "";
    },
    "TENANT=WEIGHT");

std::chrono::milliseconds milliseconds(double seconds) {
  return std::chrono::milliseconds(int64_t(std::ceil(seconds * 1000)));
}

}  // namespace shadow::service
