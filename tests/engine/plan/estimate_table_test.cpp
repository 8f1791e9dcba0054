// Issue 51: admission's memory estimate against what a render allocates, on the grid of
// tests/common/estimate_grid.hpp (every technique, filter and product, maps up to 8192^2).
// Memory is deterministic: each case's estimated device bytes over the peak of its buffers
// (from empty workspaces) must lie in [0.5, 3]. Below 0.5 the budget would admit what does not
// fit; above 3 it would refuse what does. The same grid's time estimates are a benchmark
// (build/tests/bench/cost-check, docs/benchmarks.md): time is not asserted in tests.
//
// CSM at M = 16 over 4096^2 and 8192^2 maps (7-40 GB, seconds of device time) is in the
// benchmark only: every CSM buffer grows with the map's texels, so the 2048^2 rows here hold
// their ratio; 8192^2 maps are here for the other filters.
#include <gtest/gtest.h>

#include <cstdio>

#include "engine/engine.hpp"
#include "engine/plan/cost.hpp"
#include "engine/plan/plan.hpp"
#include "estimate_grid.hpp"

namespace shadow {
namespace {

TEST(EstimateTable, MemoryEstimatesAreWithinHalfAndThreeTimesThePeak) {
  EngineOptions o;
  o.max_request_cost_ms = 0;
  o.max_output_bytes = uint64_t{4} << 30;  // an 8192^2 map with its mips and SAT
  o.max_concurrent = 1;
  o.idle_trim_delay_ms = 0;  // every request starts from empty workspaces
  o.idle_memory_bytes = 0;
  Engine engine(o);
  std::printf(
      "| case | estimate MiB | peak MiB | estimate / peak |\n| --- | ---: | ---: | ---: |\n");
  for (const testing::EstimateCase& c : testing::estimate_grid(320, 180, 2048, 2048)) {
    const CostEstimate cost = estimate_cost(c.request, make_plan(c.request));
    engine.reset_buffer_peak();
    engine.render(c.request);
    const double peak = double(engine.buffer_peak_bytes());
    const double ratio = double(cost.device_bytes) / peak;
    std::printf("| %s | %.1f | %.1f | %.2f |\n", c.name.c_str(), cost.device_bytes / 1048576.0,
                peak / 1048576.0, ratio);
    EXPECT_GE(ratio, 0.5) << c.name;
    EXPECT_LE(ratio, 3.0) << c.name;
  }
}

}  // namespace
}  // namespace shadow
