// shadowctl's progress on stderr (issue 54): the line's words, a bar drawn in place and cleared
// on a terminal, and plain lines, at most one every kLineEvery, elsewhere.
#include "shadowctl/progress_display.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <thread>

namespace shadow::ctl {
namespace {

using ::testing::HasSubstr;

v1::Progress progress(double fraction, const std::string& phase = "shadow_map.raster") {
  v1::Progress p;
  p.set_phase(phase);
  p.set_fraction(fraction);
  p.set_device_ms(1200);
  p.set_estimate_ms(2900);
  return p;
}

// What a display wrote to its stream.
std::string written(bool terminal, const std::vector<v1::Progress>& shown, bool pause = false) {
  char* text = nullptr;
  size_t size = 0;
  FILE* out = open_memstream(&text, &size);
  {
    ProgressDisplay display(out, terminal);
    for (const v1::Progress& p : shown) {
      display.show(p);
      if (pause) std::this_thread::sleep_for(ProgressDisplay::kLineEvery);
    }
  }
  std::fclose(out);
  std::string s(text, size);
  std::free(text);
  return s;
}

TEST(ProgressDisplay, TheLineSaysHowFarWhereAndOfWhat) {
  EXPECT_EQ(progress_line(progress(0.417)),
            "progress:  41% shadow_map.raster, 1.2 of ~2.9 s of device time");
  v1::Progress frame = progress(0.5, "");
  frame.set_frames_done(2);
  frame.set_frames(30);
  frame.set_estimate_ms(0);
  EXPECT_EQ(progress_line(frame), "progress:  50% frame 3 of 30, starting");
  v1::Progress goal = progress(0.0);
  goal.set_estimate_ms(0);  // a quality goal's: no estimate
  EXPECT_EQ(progress_line(goal), "progress:   0% shadow_map.raster, 1.2 s of device time");
}

TEST(ProgressDisplay, PlainLinesAtMostOneEveryKLineEvery) {
  // Two messages at once: one line; two apart: two lines, each with its percentage.
  const std::string burst = written(false, {progress(0.1), progress(0.2)});
  EXPECT_EQ(burst, progress_line(progress(0.1)) + "\n");
  const std::string paced = written(false, {progress(0.1), progress(0.2)}, true);
  EXPECT_EQ(paced, progress_line(progress(0.1)) + "\n" + progress_line(progress(0.2)) + "\n");
}

TEST(ProgressDisplay, ABarOnATerminalIsRedrawnAndCleared) {
  const std::string bar = written(true, {progress(0.5), progress(1.0)});
  EXPECT_EQ(bar.rfind("\r[###############               ]  50% shadow_map.raster", 0), 0u) << bar;
  EXPECT_THAT(bar, HasSubstr("\r[##############################] 100% "));
  EXPECT_EQ(bar.substr(bar.size() - 4), "\r\033[K") << "cleared when done";
  EXPECT_EQ(bar.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace shadow::ctl
