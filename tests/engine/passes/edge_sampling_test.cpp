// TECHNIQUE_AUTO's trial measure (kernels/edge_sampling.cl): the mean of
// |hard - filtered| over the pixels both see, against the double-precision mean the bench
// reports from the two tests (oracle::edge_sampling_estimate).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "engine/passes/edge_sampling.hpp"
#include "oracle/metrics.hpp"

namespace shadow {
namespace {

TEST(EdgeSampling, KernelIsTheOraclesMean) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  EdgeSamplingPass pass(runtime, kernels);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  // One pixel, a row, a column, ragged sizes and 1080p; hard 0/1, filtered soft values near the
  // edges, and pixels one of the two or both do not see (NaN).
  for (auto [w, h] : {std::pair{1u, 1u}, {17u, 1u}, {1u, 23u}, {333u, 77u}, {1920u, 1080u}}) {
    std::vector<float> hard(size_t{w} * h), soft(size_t{w} * h);
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        const size_t i = size_t{y} * w + x;
        const float s = std::sin(0.11f * float(x)) * std::cos(0.07f * float(y));
        hard[i] = s > 0.2f ? 0.0f : 1.0f;
        soft[i] = std::abs(s - 0.2f) < 0.1f ? u(rng) : hard[i];
        const float r = u(rng);
        if (r < 0.05f) hard[i] = NAN;
        if (r > 0.93f) soft[i] = NAN;
      }
    // |hard - filtered|, NaN where either is: what pcf.cl's PCF_EDGE writes (pcf_test.cpp).
    std::vector<float> difference(hard.size());
    for (size_t i = 0; i < hard.size(); ++i)
      difference[i] =
          std::isnan(hard[i]) || std::isnan(soft[i]) ? NAN : std::abs(hard[i] - soft[i]);
    Timeline t;
    const double got = pass.mean(runtime.upload(difference), w, h, t);
    const double want = oracle::edge_sampling_estimate(hard, soft);
    std::printf("[ edge     ] %ux%u: %.8f (oracle %.8f), %.3f ms device\n", w, h, got, want,
                t.timings().at(0).device_ms);
    // Float row sums of at most 1920 terms in [0, 1]: measured within 2e-7 relative.
    EXPECT_NEAR(got, want, 1e-6 * want + 1e-12) << w << "x" << h;
  }
  Timeline t;
  const std::vector<float> unseen(64, NAN), agree(64, 0.0f);
  EXPECT_EQ(pass.mean(runtime.upload(unseen), 8, 8, t), 0.0);
  EXPECT_EQ(pass.mean(runtime.upload(agree), 8, 8, t), 0.0);
}

}  // namespace
}  // namespace shadow
