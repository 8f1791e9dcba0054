// The GPU shape of the SAT and mip passes (the _gpu kernels of kernels/summed_area.cl and
// mip_pyramid.cl; issue 42) on the device at hand: bit-identical to the CPU shape (memcmp) and
// within the bounds of the same double-precision references as prefilter_test.cpp
// (prefilter_reference.hpp), at sizes that are not multiples of the work-group or the strips, one
// texel wide or high, and with several channels; then whole renders forced to each profile, whose
// textures must be the same bytes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "engine/engine.hpp"
#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/summed_area.hpp"
#include "engine_fixture.hpp"
#include "occluder_scene.hpp"
#include "prefilter_reference.hpp"

namespace shadow {
namespace {

using testing::box_direct;
using testing::cpu_downsample;
using testing::Image;

// One device with its kernels forced to one shape.
struct Shape : testing::ProfileDevice {
  using ProfileDevice::ProfileDevice;
  MipPyramidPass mips{runtime, kernels};
  SummedAreaPass sat{runtime, kernels};
  cl::Buffer input, filtered;

  template <typename T>
  DeviceTexture upload(const std::vector<T>& v, uint32_t w, uint32_t h, uint32_t c) {
    runtime.ensure(input, v.size() * sizeof(T));
    runtime.write(input, v.data(), v.size() * sizeof(T));
    return {&input, w, h, c};
  }
};

Shape& cpu() {
  static Shape s("cpu");
  return s;
}
Shape& gpu() {
  static Shape s("gpu");
  return s;
}

TEST(PrefilterShapes, TheProfilesAreForced) {
  EXPECT_EQ(cpu().runtime.device_info().profile().shape, cl::KernelShape::kCpu);
  EXPECT_EQ(gpu().runtime.device_info().profile().shape, cl::KernelShape::kGpu);
  std::printf("GPU shape: work-groups of %zu\n", gpu().runtime.device_info().profile().group_size);
}

// Values in [-1, 1], a third of them scaled down by 2^-10 .. 2^-40: rows whose double prefixes
// round (a float of 1e-9 beside ones does not add exactly), so a summation order other than
// The CPU shape's would move some entries by a quantum. Some NaN.
Image hard_image(uint32_t w, uint32_t h, uint32_t c, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> scale(10, 40), kind(0, 29);
  Image im{w, h, c, std::vector<float>(size_t{w} * h * c)};
  for (float& x : im.v) {
    const int k = kind(rng);
    x = k == 0 ? NAN : k < 10 ? std::ldexp(u(rng), -scale(rng)) : u(rng);
  }
  return im;
}

bool same_bytes(const void* a, const void* b, size_t bytes) {
  return bytes == 0 || std::memcmp(a, b, bytes) == 0;
}

// The quantum sat_scale picks for `im`.
double quantum(const Image& im) {
  double m = 0;
  for (float x : im.v)
    if (!std::isnan(x)) m = std::max(m, double(std::abs(x)));
  const double bound = m * im.w * im.h;
  int e = 0;
  if (bound > 0) std::frexp(bound, &e);
  return bound > 0 ? std::ldexp(1.0, e - 51) : 1.0;
}

const std::vector<std::tuple<uint32_t, uint32_t, uint32_t>> kSatSizes = {
    {1, 1, 1},    {3, 5, 1},     {3, 5, 3},   {1, 300, 1},  {2100, 1, 1},
    {2100, 5, 2}, {1030, 9, 4},  {9, 3, 8},   {70, 3, 5},   {300, 7, 16},
    {261, 4, 4},  {300, 257, 1}, {37, 70, 3}, {4100, 3, 1}, {517, 33, 2}};

TEST(PrefilterShapes, SatTablesAreBitIdenticalAndMatchTheReference) {
  for (auto [w, h, c] : kSatSizes) {
    const Image im = hard_image(w, h, c, w * 13 + h * 7 + c);
    std::vector<double> tables[2];
    int i = 0;
    for (Shape* s : {&cpu(), &gpu()}) {
      Timeline t;
      const SummedAreaTable& table = s->sat.run(s->upload(im.v, w, h, c), "test.sat", t);
      tables[i++] = s->read<double>(table.sums, im.v.size());
    }
    EXPECT_TRUE(same_bytes(tables[0].data(), tables[1].data(), im.v.size() * sizeof(double)))
        << w << "x" << h << " x" << c;
    // Each entry against the table summed in long double: every row's prefix rounds to the
    // quantum once (half a quantum) after its own double sums (far less, but give it as much).
    const std::vector<double>& sat = tables[1];
    const double q = quantum(im);
    double worst = 0;  // in quanta per row summed
    for (uint32_t ch = 0; ch < c; ++ch) {
      std::vector<long double> column(w, 0);
      for (uint32_t y = 0; y < h; ++y) {
        long double row = 0;
        for (uint32_t x = 0; x < w; ++x) {
          const float v = im.at(x, y, ch);
          row += std::isnan(v) ? 0 : v;
          column[x] += row;
          const double err = std::abs(double(sat[(size_t{y} * w + x) * c + ch] - column[x]));
          worst = std::max(worst, err / q / (y + 1));
        }
      }
    }
    std::printf("sat %ux%u x%u: GPU shape %s, worst entry error %.3g quanta per row\n", w, h, c,
                tables[0] == tables[1] ? "identical" : "DIFFERENT", worst);
    EXPECT_LE(worst, 1.0) << w << "x" << h << " x" << c;
  }
}

TEST(PrefilterShapes, SatBoxFilterIsBitIdenticalAndMatchesTheReference) {
  for (auto [w, h, c, r] : {std::tuple{1u, 1u, 1u, 2u},
                            {3u, 5u, 2u, 1u},
                            {300u, 40u, 1u, 5u},
                            {70u, 9u, 5u, 3u},
                            {1u, 260u, 1u, 4u}}) {
    std::mt19937 rng(w + 3 * h);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    Image im{w, h, c, std::vector<float>(size_t{w} * h * c)};
    for (float& x : im.v) x = u(rng);
    std::vector<float> outs[2];
    int i = 0;
    for (Shape* s : {&cpu(), &gpu()}) {
      Timeline t;
      const SummedAreaTable& table = s->sat.run(s->upload(im.v, w, h, c), "test.sat", t);
      s->sat.box_filter(table, r, r + 1, s->filtered, "test.box", t);
      outs[i++] = s->read<float>(s->filtered, im.v.size());
    }
    EXPECT_TRUE(same_bytes(outs[0].data(), outs[1].data(), im.v.size() * sizeof(float)))
        << w << "x" << h << " x" << c;
    double err = 0;
    for (uint32_t ch = 0; ch < c; ++ch)
      for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
          const int x0 = std::max(0, int(x) - int(r)), x1 = std::min(int(w) - 1, int(x + r));
          const int y0 = std::max(0, int(y) - int(r) - 1),
                    y1 = std::min(int(h) - 1, int(y + r + 1));
          const double ref =
              double(box_direct(im, ch, x0, y0, x1, y1)) / (double(x1 - x0 + 1) * (y1 - y0 + 1));
          err = std::max(err, std::abs(outs[1][(size_t{y} * w + x) * c + ch] - ref));
        }
    std::printf("sat box filter %ux%u x%u r=%u, GPU shape: max error %.3g\n", w, h, c, r, err);
    EXPECT_LT(err, 1e-7);
  }
}

TEST(PrefilterShapes, MipChainsAreBitIdenticalAndMatchTheReference) {
  for (auto [w, h, c] : {std::tuple{1u, 1u, 1u},
                         {3u, 5u, 1u},
                         {3u, 5u, 3u},
                         {7u, 2u, 2u},
                         {129u, 67u, 4u},
                         {1000u, 1u, 1u},
                         {1u, 1000u, 1u},
                         {300u, 257u, 1u},
                         {37u, 23u, 17u}}) {
    std::mt19937 rng(w * 31 + h + c);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    Image im{w, h, c, std::vector<float>(size_t{w} * h * c)};
    for (float& x : im.v) x = u(rng) < 0.2f ? NAN : u(rng);
    std::vector<float> chains[2];
    std::vector<MipLevel> levels;
    int i = 0;
    for (Shape* s : {&cpu(), &gpu()}) {
      Timeline t;
      const MipChain& chain = s->mips.run(s->upload(im.v, w, h, c), "test.mips", t);
      chains[i++] = s->read<float>(chain.storage, chain.floats);
      levels = chain.levels;
    }
    EXPECT_TRUE(same_bytes(chains[0].data(), chains[1].data(), chains[0].size() * sizeof(float)))
        << w << "x" << h << " x" << c;
    std::vector<double> ref(im.v.begin(), im.v.end());
    uint32_t lw = w, lh = h;
    double err = 0;
    for (const MipLevel& l : levels) {
      ref = cpu_downsample(ref, lw, lh, c, l.width, l.height);
      for (size_t k = 0; k < ref.size(); ++k) {
        const float g = chains[1][l.offset + k];
        ASSERT_EQ(std::isnan(ref[k]), std::isnan(g)) << w << "x" << h << " x" << c;
        if (!std::isnan(g)) err = std::max(err, std::abs(g - ref[k]));
      }
      lw = l.width;
      lh = l.height;
    }
    std::printf("mips %ux%u x%u, GPU shape: max error %.3g\n", w, h, c, err);
    EXPECT_LT(err, 1e-6);
  }
}

// CSM bases' path: levels written in place after level 0, float or half texels.
TEST(PrefilterShapes, MipsInPlaceAreBitIdenticalInFloatAndHalf) {
  for (auto [w, h, c] : {std::tuple{256u, 256u, 4u}, {75u, 75u, 1u}, {33u, 33u, 3u}}) {
    const std::vector<MipLevel> levels = mip_levels(w, h);
    const size_t base = size_t{w} * h;
    const size_t elements = (base + levels.back().offset + 1) * c;  // the last level is 1x1
    std::mt19937 rng(w + c);
    for (bool half : {false, true}) {
      std::vector<float> floats(elements, 0.0f);
      std::vector<uint16_t> halves(elements, 0);
      std::uniform_real_distribution<float> u(-1.0f, 1.0f);
      for (size_t k = 0; k < base * c; ++k) floats[k] = u(rng);
      for (size_t k = 0; k < base * c; ++k) {  // finite halves, some NaN
        uint16_t bits = uint16_t(rng());
        if ((bits >> 10 & 31) == 31) bits = k % 7 ? uint16_t(bits & ~0x4000) : 0x7e00;
        halves[k] = bits;
      }
      const size_t bytes = elements * (half ? 2 : 4);
      std::vector<uint8_t> out[2];
      int i = 0;
      for (Shape* s : {&cpu(), &gpu()}) {
        Timeline t;
        const DeviceTexture tex = half ? s->upload(halves, w, h, c) : s->upload(floats, w, h, c);
        s->mips.run_in_place(*tex.buffer, w, h, c, half, "test.mips", t);
        out[i++] = s->read<uint8_t>(*tex.buffer, bytes);
      }
      EXPECT_TRUE(same_bytes(out[0].data(), out[1].data(), bytes))
          << w << "x" << h << " x" << c << (half ? " half" : " float");
    }
  }
}

// Whole renders on two engines, one per profile: every texture the same bytes.
void expect_same_textures(const RenderRequest& r, const std::string& what) {
  const RenderResult a = testing::engine("cpu").render(r), b = testing::engine("gpu").render(r);
  ASSERT_EQ(a.textures.size(), b.textures.size()) << what;
  for (size_t i = 0; i < a.textures.size(); ++i) {
    const Texture &x = a.textures[i], &y = b.textures[i];
    ASSERT_EQ(x.name, y.name) << what;
    ASSERT_EQ(x.data.size(), y.data.size()) << what << " " << x.name;
    ASSERT_EQ(x.data64.size(), y.data64.size()) << what << " " << x.name;
    ASSERT_EQ(x.data16.size(), y.data16.size()) << what << " " << x.name;
    EXPECT_TRUE(same_bytes(x.data.data(), y.data.data(), x.data.size() * sizeof(float)) &&
                same_bytes(x.data64.data(), y.data64.data(), x.data64.size() * sizeof(double)) &&
                same_bytes(x.data16.data(), y.data16.data(), x.data16.size() * sizeof(uint16_t)))
        << what << ": " << x.name << " differs between the profiles";
  }
  size_t prefilter_passes = 0;
  for (const std::string& p : b.passes)
    prefilter_passes += p.find(".sat") != std::string::npos || p.find("mips") != std::string::npos;
  std::printf("%s: %zu textures identical under both profiles (%zu SAT and mip passes)\n",
              what.c_str(), b.textures.size(), prefilter_passes);
  EXPECT_GT(prefilter_passes, 0u) << what;
}

RenderRequest small_request() {
  RenderRequest r = testing::occluder_request();
  r.camera.width = 203;  // not powers of two
  r.camera.height = 117;
  r.shadow_map.size = 300;
  return r;
}

TEST(PrefilterShapes, RendersUnderEitherProfileAreBitIdentical) {
  RenderRequest r = small_request();
  r.filter.kind = FilterKind::kPoisson;  // fractional visibilities
  r.products = {Product::kVisibility, Product::kVisibilityMips, Product::kVisibilitySat,
                Product::kShadowMap,  Product::kShadowMapMips,  Product::kShadowMapSat};
  expect_same_textures(r, "map and visibility, mips and SATs");

  // CSM bases prefiltered by mips (float and half) and SATs; 3 terms take summed_area.cl's
  // channel-at-a-time path, 4 its vector path.
  for (auto [lookup, storage, terms] : {std::tuple{CsmLookup::kMips, CsmStorage::kFloat32, 4u},
                                        {CsmLookup::kMips, CsmStorage::kFloat16, 4u},
                                        {CsmLookup::kSat, CsmStorage::kFloat32, 4u},
                                        {CsmLookup::kSat, CsmStorage::kFloat32, 3u}}) {
    RenderRequest c = small_request();
    c.shadow_map.size = 260;
    c.lights[0].size = 2.0f;
    c.filter.kind = FilterKind::kPcssCsm;
    c.filter.csm.terms = terms;
    c.filter.csm.lookup = lookup;
    c.filter.csm.storage = storage;
    c.products = {Product::kVisibility, Product::kCsmBasis, Product::kBlockerDepth};
    expect_same_textures(c, std::string("PCSS-CSM, ") +
                                (lookup == CsmLookup::kSat ? "SAT" : "mips") + ", " +
                                (storage == CsmStorage::kFloat16 ? "half" : "float") + ", " +
                                std::to_string(terms) + " terms");
  }
}

}  // namespace
}  // namespace shadow
