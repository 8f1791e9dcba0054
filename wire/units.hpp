// Durations and sizes as people read them in messages: a limit of 0.001 ms must not print as
// "0 ms", nor 65 minutes as "3900000 ms" (issue 51).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace shadow {

// "0.001 ms", "12.5 ms", "916 ms", "11.6 s", "65.2 min": three significant digits.
inline std::string ms_text(double ms) {
  char text[48];
  if (ms < 999.5)
    std::snprintf(text, sizeof text, "%.3g ms", ms);
  else if (ms < 599.5e3)
    std::snprintf(text, sizeof text, "%.3g s", ms / 1e3);
  else if (ms < 999.5 * 60e3)
    std::snprintf(text, sizeof text, "%.3g min", ms / 60e3);
  else
    std::snprintf(text, sizeof text, "%.0f min", ms / 60e3);
  return text;
}

// "123 bytes", "4.5 MiB (4718592 bytes)": the exact count with a readable size beside it.
inline std::string bytes_text(uint64_t bytes) {
  if (bytes < 1024 * 1024) return std::to_string(bytes) + " bytes";
  char text[64];
  const double mib = double(bytes) / (1024.0 * 1024.0);
  if (mib < 1024)
    std::snprintf(text, sizeof text, "%.3g MiB (%llu bytes)", mib, (unsigned long long)bytes);
  else
    std::snprintf(text, sizeof text, "%.3g GiB (%llu bytes)", mib / 1024,
                  (unsigned long long)bytes);
  return text;
}

}  // namespace shadow
