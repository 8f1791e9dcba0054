#include "shadowctl/progress_display.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace shadow::ctl {

std::string progress_line(const v1::Progress& p) {
  char text[96];
  const int percent = int(std::floor(100 * std::clamp(p.fraction(), 0.0, 1.0)));
  std::snprintf(text, sizeof text, "progress: %3d%% ", percent);
  std::string line = text;
  if (p.frames() > 0)
    line += "frame " + std::to_string(std::min(p.frames_done() + 1, p.frames())) + " of " +
            std::to_string(p.frames()) + ", ";
  line += p.phase().empty() ? "starting" : p.phase();
  // A sequence's frame times are its frames' own, mostly too small to say much: its count does.
  if (p.frames() > 0) return line;
  if (p.estimate_ms() > 0)
    std::snprintf(text, sizeof text, ", %.1f of ~%.1f s of device time", p.device_ms() / 1000,
                  p.estimate_ms() / 1000);
  else
    std::snprintf(text, sizeof text, ", %.1f s of device time", p.device_ms() / 1000);
  return line + text;
}

ProgressDisplay::ProgressDisplay(FILE* out) : ProgressDisplay(out, isatty(fileno(out)) == 1) {}

ProgressDisplay::ProgressDisplay(FILE* out, bool terminal) : out_(out), terminal_(terminal) {}

void ProgressDisplay::show(const v1::Progress& p) {
  if (!terminal_) {
    const auto now = std::chrono::steady_clock::now();
    if (drawn_ && now - last_ < kLineEvery) return;
    last_ = now;
    drawn_ = true;
    std::fprintf(out_, "%s\n", progress_line(p).c_str());
    std::fflush(out_);
    return;
  }
  constexpr int kWidth = 30;
  const int filled = int(std::lround(kWidth * std::clamp(p.fraction(), 0.0, 1.0)));
  const std::string bar = std::string(filled, '#') + std::string(kWidth - filled, ' ');
  // "\r" to the line's start, the bar, and "\033[K" to clear what a longer line left.
  std::fprintf(out_, "\r[%s] %s\033[K", bar.c_str(), progress_line(p).substr(10).c_str());
  std::fflush(out_);
  drawn_ = true;
}

void ProgressDisplay::done() {
  if (terminal_ && drawn_) {
    std::fprintf(out_, "\r\033[K");
    std::fflush(out_);
  }
  drawn_ = false;
}

}  // namespace shadow::ctl
