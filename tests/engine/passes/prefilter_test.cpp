// Mip pyramids and summed-area tables against CPU references: double-precision mips, and box
// sums summed directly in long double (a double SAT itself drifts by ~1e-7 at 8192^2).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/summed_area.hpp"
#include "prefilter_reference.hpp"

namespace shadow {
namespace {

using testing::box_direct;
using testing::cpu_downsample;
using testing::Image;

struct Device {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  MipPyramidPass mips{runtime, kernels};
  SummedAreaPass sat{runtime, kernels};
  cl::Buffer input, filtered;
};

Device& device() {
  static Device d;
  return d;
}

Image random_image(uint32_t w, uint32_t h, uint32_t c, uint32_t seed, float nan_fraction = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Image im{w, h, c, std::vector<float>(size_t{w} * h * c)};
  for (float& x : im.v) x = u(rng) < nan_fraction ? NAN : u(rng);
  return im;
}

DeviceTexture upload(const Image& im) {
  Device& d = device();
  d.runtime.ensure(d.input, im.v.size() * sizeof(float));
  d.runtime.write(d.input, im.v.data(), im.v.size() * sizeof(float));
  return {&d.input, im.w, im.h, im.c};
}

// Largest |GPU - reference| over every level (NaN must match NaN).
double mip_error(const Image& im) {
  Device& d = device();
  Timeline t;
  const MipChain& chain = d.mips.run(upload(im), "test.mips", t);
  std::vector<float> gpu(chain.floats);
  if (!gpu.empty()) d.runtime.read(chain.storage, gpu.data(), gpu.size() * sizeof(float));
  std::vector<double> ref(im.v.begin(), im.v.end());
  uint32_t w = im.w, h = im.h;
  double err = 0;
  for (const MipLevel& l : chain.levels) {
    ref = cpu_downsample(ref, w, h, im.c, l.width, l.height);
    for (size_t i = 0; i < ref.size(); ++i) {
      const float g = gpu[l.offset + i];
      if (std::isnan(ref[i]) != std::isnan(g)) return INFINITY;
      if (!std::isnan(g)) err = std::max(err, std::abs(g - ref[i]));
    }
    w = l.width;
    h = l.height;
  }
  return err;
}

TEST(Mips, LevelSizesAreFloorHalvesDownToOne) {
  EXPECT_TRUE(mip_levels(1, 1).empty());
  const auto l = mip_levels(3, 5);
  ASSERT_EQ(l.size(), 2u);
  EXPECT_EQ(l[0].width, 1u);
  EXPECT_EQ(l[0].height, 2u);
  EXPECT_EQ(l[1].width, 1u);
  EXPECT_EQ(l[1].height, 1u);
  EXPECT_EQ(mip_levels(4096, 4096).size(), 12u);
}

TEST(Mips, SmallAndOddSizesMatchTheDoubleReference) {
  for (auto [w, h, c] : {std::tuple{1u, 1u, 1u},
                         {3u, 5u, 1u},
                         {3u, 5u, 3u},
                         {7u, 2u, 2u},
                         {129u, 67u, 4u},
                         {1000u, 1u, 1u}}) {
    const double err = mip_error(random_image(w, h, c, w * 31 + h));
    std::printf("mips %ux%u x%u: max error %.3g\n", w, h, c, err);
    EXPECT_LT(err, 1e-6) << w << "x" << h << " x" << c;
  }
}

TEST(Mips, NanTexelsAreLeftOut) {
  const double err = mip_error(random_image(37, 23, 2, 5, 0.3f));
  std::printf("mips with 30%% NaN: max error %.3g\n", err);
  EXPECT_LT(err, 1e-6);
}

TEST(Mips, Size4096MatchesTheDoubleReference) {
  const double err = mip_error(random_image(4096, 4096, 1, 7));
  std::printf("mips 4096^2: max error %.3g\n", err);
  EXPECT_LT(err, 1e-6);
}

TEST(Mips, Size8192MatchesTheDoubleReference) {
  const double err = mip_error(random_image(8192, 8192, 1, 8));
  std::printf("mips 8192^2: max error %.3g\n", err);
  EXPECT_LT(err, 1e-6);
}

std::vector<double> read_sat(const SummedAreaTable& s) {
  std::vector<double> out(size_t{s.width} * s.height * s.channels);
  device().runtime.read(s.sums, out.data(), out.size() * sizeof(double));
  return out;
}

double box_from_sat(const std::vector<double>& sat, const Image& im, uint32_t ch, int x0, int y0,
                    int x1, int y1) {  // inclusive corners
  auto S = [&](int x, int y) {
    return x < 0 || y < 0 ? 0.0 : sat[(size_t(y) * im.w + size_t(x)) * im.c + ch];
  };
  return S(x1, y1) - S(x0 - 1, y1) - S(x1, y0 - 1) + S(x0 - 1, y0 - 1);
}

TEST(Sat, EveryEntryOfSmallTablesMatches) {
  for (auto [w, h, c] : {std::tuple{1u, 1u, 1u},
                         {3u, 5u, 1u},
                         {3u, 5u, 3u},
                         {300u, 7u, 1u},
                         {517u, 9u, 2u},
                         {261u, 4u, 4u},
                         {9u, 3u, 8u},
                         {70u, 3u, 5u},
                         {2100u, 5u, 2u}}) {  // several strips, two channels
    const Image im = random_image(w, h, c, w + 7 * h + c, 0.05f);
    Timeline t;
    const std::vector<double> sat = read_sat(device().sat.run(upload(im), "test.sat", t));
    double err = 0;
    for (uint32_t ch = 0; ch < c; ++ch)
      for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
          err = std::max<double>(err, std::abs(box_from_sat(sat, im, ch, 0, 0, x, y) -
                                               box_direct(im, ch, 0, 0, x, y)));
    std::printf("sat %ux%u x%u: max entry error %.3g\n", w, h, c, err);
    EXPECT_LT(err, 1e-12) << w << "x" << h << " x" << c;
  }
}

// Small boxes anywhere (far corners included) and a few huge ones: the worst error of the box
// average and of the sum relative to itself.
void check_boxes(uint32_t size) {
  const Image im = random_image(size, size, 1, size);
  Timeline t;
  const std::vector<double> sat = read_sat(device().sat.run(upload(im), "test.sat", t));
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pos(0, int(size) - 1), ext(0, 15);
  double worst_avg = 0, worst_rel = 0;
  for (int i = 0; i < 20000; ++i) {
    int x0 = pos(rng), y0 = pos(rng);
    if (i % 2) x0 = int(size) - 1 - ext(rng), y0 = int(size) - 1 - ext(rng);  // far from origin
    const int x1 = std::min(int(size) - 1, x0 + ext(rng)),
              y1 = std::min(int(size) - 1, y0 + ext(rng));
    const double area = double(x1 - x0 + 1) * (y1 - y0 + 1);
    const long double ref = box_direct(im, 0, x0, y0, x1, y1);
    const double err = std::abs(double(box_from_sat(sat, im, 0, x0, y0, x1, y1) - ref));
    worst_avg = std::max(worst_avg, err / area);
    if (ref > 0) worst_rel = std::max(worst_rel, double(err / ref));
  }
  for (int big : {0, 1}) {
    const int lo = big ? 1 : 0, hi = int(size) - 1 - lo;
    const long double ref = box_direct(im, 0, lo, lo, hi, hi);
    const double err = std::abs(double(box_from_sat(sat, im, 0, lo, lo, hi, hi) - ref));
    worst_rel = std::max(worst_rel, double(err / ref));
  }
  std::printf("sat %u^2: worst box-average error %.3g, worst relative sum error %.3g\n", size,
              worst_avg, worst_rel);
  EXPECT_LT(worst_avg, 1e-7);  // measured 2.5e-8 at 8192^2; the requirement is 1e-6
  EXPECT_LT(worst_rel, 1e-5);
}

TEST(Sat, BoxSumsAt4096) {
  check_boxes(4096);
}
TEST(Sat, BoxSumsAt8192) {
  check_boxes(8192);
}

TEST(Sat, BoxFilterKernelAveragesTheClippedBox) {
  for (auto [w, h, c, r] : {std::tuple{1u, 1u, 1u, 2u}, {3u, 5u, 2u, 1u}, {300u, 40u, 1u, 5u}}) {
    const Image im = random_image(w, h, c, 11 * w + h);
    Device& d = device();
    Timeline t;
    const SummedAreaTable& sat = d.sat.run(upload(im), "test.sat", t);
    d.sat.box_filter(sat, r, r + 1, d.filtered, "test.box", t);
    std::vector<float> out(im.v.size());
    d.runtime.read(d.filtered, out.data(), out.size() * sizeof(float));
    double err = 0;
    for (uint32_t ch = 0; ch < c; ++ch)
      for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
          const int x0 = std::max(0, int(x) - int(r)), x1 = std::min(int(w) - 1, int(x + r));
          const int y0 = std::max(0, int(y) - int(r) - 1),
                    y1 = std::min(int(h) - 1, int(y + r + 1));
          const double ref =
              double(box_direct(im, ch, x0, y0, x1, y1)) / (double(x1 - x0 + 1) * (y1 - y0 + 1));
          err = std::max(err, std::abs(out[(size_t{y} * w + x) * c + ch] - ref));
        }
    std::printf("sat box filter %ux%u x%u r=%u: max error %.3g\n", w, h, c, r, err);
    EXPECT_LT(err, 1e-7);
  }
}

}  // namespace
}  // namespace shadow
