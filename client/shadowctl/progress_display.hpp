// How shadowctl shows the server's Progress messages on stderr: on a terminal one bar, redrawn in
// place and cleared when the work is done; elsewhere (a log, a pipe) plain lines, each with its
// percentage ("NN%"), at most one every kLineEvery (the server sends one every ~250 ms, so a
// line comes at least once a second).
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

#include "shadow/v1/shadow.pb.h"

namespace shadow::ctl {

// "progress:  42% shadow_map.raster, 1.2 of ~2.9 s of device time"; a sequence's
// "progress:  42% frame 13 of 30, shadow_map.raster".
std::string progress_line(const v1::Progress& progress);

class ProgressDisplay {
 public:
  static constexpr std::chrono::milliseconds kLineEvery{750};
  explicit ProgressDisplay(FILE* out);  // a terminal or not, as isatty() says
  ProgressDisplay(FILE* out, bool terminal);
  ~ProgressDisplay() { done(); }

  void show(const v1::Progress& progress);
  // Clears the bar (a terminal) so that what follows starts on a clean line.
  void done();

 private:
  FILE* out_;
  bool terminal_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace shadow::ctl
