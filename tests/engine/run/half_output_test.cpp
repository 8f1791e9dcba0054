// PIXEL_FORMAT_FLOAT16 outputs (RenderRequest::output_format): every float product of a request
// is, value by value, the float32 product of the same request rounded to the nearest binary16
// (ties to even), as a double-precision CPU rounding computes it; SATs stay float64 and equal.
// Also prints the largest difference per product (docs/benchmarks.md, "Float16 outputs").
#include <gtest/gtest.h>

#include <cfenv>
#include <cmath>
#include <cstdio>

#include "occluder_scene.hpp"

namespace shadow {
namespace {

// Binary16 bits of `f`, rounded to nearest even, computed in double (independent of the
// device's vstore_half_rte). NaN is left to the caller.
uint16_t reference_half(float f) {
  const uint16_t sign = std::signbit(f) ? 0x8000 : 0;
  const double a = std::fabs(double(f));
  if (std::isinf(a) || a >= 65520.0) return sign | 0x7c00;  // 65520 rounds up past 65504
  if (a < std::ldexp(1.0, -14)) {  // subnormal: multiples of 2^-24 (1024 -> the least normal)
    return sign | uint16_t(std::nearbyint(a * std::ldexp(1.0, 24)));
  }
  int e = 0;
  std::frexp(a, &e);  // a = m 2^e, m in [0.5, 1)
  int exponent = e - 1;
  double q = std::nearbyint(a * std::ldexp(1.0, 10 - exponent));  // 1024..2048
  if (q == 2048) q = 1024, ++exponent;
  if (exponent + 15 >= 31) return sign | 0x7c00;
  return sign | uint16_t((exponent + 15) << 10) | uint16_t(q - 1024);
}

double half_value(uint16_t h) {
  const int exponent = (h >> 10) & 31, mantissa = h & 1023;
  const double magnitude = exponent == 0 ? std::ldexp(double(mantissa), -24)
                                         : std::ldexp(1.0 + mantissa / 1024.0, exponent - 15);
  return (h & 0x8000) ? -magnitude : magnitude;
}

TEST(HalfReference, KnownValues) {
  EXPECT_EQ(reference_half(1.0f), 0x3c00);
  EXPECT_EQ(reference_half(-2.0f), 0xc000);
  EXPECT_EQ(reference_half(65504.0f), 0x7bff);
  EXPECT_EQ(reference_half(65519.0f), 0x7bff);
  EXPECT_EQ(reference_half(65520.0f), 0x7c00);
  EXPECT_EQ(reference_half(std::ldexp(1.0f, -24)), 0x0001);
  EXPECT_EQ(reference_half(std::ldexp(1.0f, -25)), 0x0000);             // a tie, to even
  EXPECT_EQ(reference_half(1.0f + std::ldexp(1.0f, -11)), 0x3c00);      // a tie, to even
  EXPECT_EQ(reference_half(1.0f + 3 * std::ldexp(1.0f, -11)), 0x3c02);  // a tie, to even
  EXPECT_EQ(reference_half(0.1f), 0x2e66);
}

void expect_rounded(const Texture& f32, const Texture& f16, double& worst) {
  ASSERT_EQ(f16.format, PixelFormat::kFloat16) << f16.name;
  ASSERT_EQ(f16.data16.size(), f32.data.size()) << f16.name;
  EXPECT_TRUE(f16.data.empty());
  EXPECT_EQ(f16.byte_size() * 2, f32.byte_size());
  size_t wrong = 0;
  for (size_t i = 0; i < f32.data.size(); ++i) {
    const float v = f32.data[i];
    const uint16_t h = f16.data16[i];
    if (std::isnan(v)) {
      wrong += !((h & 0x7c00) == 0x7c00 && (h & 0x3ff) != 0);
      continue;
    }
    wrong += h != reference_half(v);
    if (std::isfinite(v) && (h & 0x7c00) != 0x7c00)
      worst = std::max(worst, std::fabs(half_value(h) - double(v)));
  }
  EXPECT_EQ(wrong, 0u) << f16.name << ": values not the nearest half";
}

void check(RenderRequest r) {
  ASSERT_EQ(std::fegetround(), FE_TONEAREST);
  const RenderResult f32 = testing::engine().render(r);
  r.output_format = PixelFormat::kFloat16;
  const RenderResult f16 = testing::engine().render(r);
  ASSERT_EQ(f16.textures.size(), f32.textures.size());
  for (size_t i = 0; i < f32.textures.size(); ++i) {
    const Texture &a = f32.textures[i], &b = f16.textures[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.faces, b.faces);
    if (a.format == PixelFormat::kFloat64) {  // SATs stay exact
      EXPECT_EQ(b.format, PixelFormat::kFloat64);
      EXPECT_EQ(a.data64, b.data64) << a.name;
      continue;
    }
    double worst = 0;
    expect_rounded(a, b, worst);
    std::printf("float16 %-22s largest difference from float32 %.3g\n", a.name.c_str(), worst);
  }
}

TEST(HalfOutput, EveryFloatProductIsTheNearestHalf) {
  RenderRequest r = testing::occluder_request();
  r.lights[0].size = 2.0f;
  r.filter.kind = FilterKind::kPcss;
  r.products = {Product::kShadowMap,      Product::kVisibility,    Product::kPosition,
                Product::kTexelDensity,   Product::kShadowMapMips, Product::kShadowMapSat,
                Product::kVisibilityMips, Product::kVisibilitySat};
  check(r);
}

TEST(HalfOutput, CubeFacesAndCsmBasis) {
  RenderRequest r = testing::occluder_request();
  r.lights[0].type = LightType::kPoint;
  r.lights[0].position = {0, 5, 0};
  r.products = {Product::kShadowMap, Product::kVisibility};
  check(r);
  RenderRequest csm = testing::occluder_request();
  csm.lights[0].size = 1.0f;
  csm.filter.kind = FilterKind::kPcssCsm;
  csm.filter.csm.terms = 4;
  csm.products = {Product::kCsmBasis, Product::kBlockerDepth, Product::kVisibility};
  check(csm);
}

// Half the reply: the reservation and the limit count two bytes a value.
TEST(HalfOutput, OutputLimitCountsTwoBytes) {
  RenderRequest r = testing::occluder_request();
  r.products = {Product::kVisibility};
  r.camera.width = 2048, r.camera.height = 2048;  // 16 MiB as float32, 8 MiB as float16
  Engine small({uint64_t{12} << 20});
  EXPECT_THROW(small.render(r), ResourceExhausted);
  r.output_format = PixelFormat::kFloat16;
  EXPECT_NO_THROW(small.render(r));
}

}  // namespace
}  // namespace shadow
