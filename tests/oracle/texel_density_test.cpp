// The texel-density reference and its statistics on closed forms.
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "oracle/texel_density.hpp"

namespace shadow::oracle {
namespace {

// Clip-space [-1, 1]^2 (y up) -> [0, 1]^2 from the top-left corner, z from [-1, 1] to [0, 1].
glm::dmat4 to_texture(const glm::dmat4& clip) {
  const glm::dmat4 m = glm::transpose(
      glm::dmat4({0.5, 0, 0, 0.5}, {0, -0.5, 0, 0.5}, {0, 0, 0.5, 0.5}, {0, 0, 0, 1}));
  return m * clip;
}

// Orthographic light over a 20 m square around the origin, travelling along `dir`.
glm::dmat4 sun(glm::dvec3 dir) {
  dir = glm::normalize(dir);
  const glm::dvec3 up = std::abs(dir.y) > 0.99 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  return to_texture(glm::ortho(-10.0, 10.0, -10.0, 10.0, 1.0, 100.0) *
                    glm::lookAt(-50.0 * dir, glm::dvec3(0.0), up));
}

// A camera `height` metres above the origin looking straight down, 60 degrees vertical fov.
glm::dmat4 down_camera(double height, double aspect) {
  return to_texture(glm::perspective(glm::radians(60.0), aspect, 0.1, 1000.0) *
                    glm::lookAt(glm::dvec3(0, height, 0), glm::dvec3(0.0), glm::dvec3(0, 0, -1)));
}

TEST(TexelDensityReference, OverheadSunAndCameraGiveTexelOverPixelSize) {
  const uint32_t map = 1024, w = 640, h = 480;
  const double height = 10.0;
  const double texel = 20.0 / map, pixel = 2.0 * height * std::tan(glm::radians(30.0)) / h;
  const double d = texel_footprint(sun({0, -1, 0}), map, down_camera(height, double(w) / h), w, h,
                                   {0, 0, 0}, {0, 1, 0});
  std::printf("density %.9f, expected %.9f\n", d, texel / pixel);
  EXPECT_NEAR(d, texel / pixel, 1e-9 * texel / pixel);
}

TEST(TexelDensityReference, SlantedSunStretchesTheFootprintByOneOverCosine) {
  const uint32_t map = 1024, w = 640, h = 480;
  const glm::dmat4 cam = down_camera(10.0, double(w) / h);
  const double overhead = texel_footprint(sun({0, -1, 0}), map, cam, w, h, {0, 0, 0}, {0, 1, 0});
  for (double deg : {30.0, 60.0, 80.0}) {
    const double a = glm::radians(deg);
    const double d =
        texel_footprint(sun({std::sin(a), -std::cos(a), 0}), map, cam, w, h, {0, 0, 0}, {0, 1, 0});
    EXPECT_NEAR(d / overhead, 1.0 / std::cos(a), 1e-9) << deg;
  }
  // Grazing exactly: the light's Jacobian is singular.
  EXPECT_TRUE(std::isinf(texel_footprint(sun({1, 0, 0}), map, cam, w, h, {0, 0, 0}, {0, 1, 0})));
  // Outside the map: NaN.
  EXPECT_TRUE(std::isnan(texel_footprint(sun({0, -1, 0}), map, cam, w, h, {11, 0, 0}, {0, 1, 0})));
}

TEST(TexelDensityStats, NearestRankPercentilesIgnoreNaN) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> v;
  for (int i = 1; i <= 100; ++i) v.push_back(0.02f * i);  // 0.02 .. 2.0
  v.push_back(kNaN);
  v.push_back(kNaN);
  const DensityStats s = density_stats(v);
  EXPECT_EQ(s.pixels, 100u);
  EXPECT_FLOAT_EQ(s.median, 1.0f);  // the 50th value
  EXPECT_FLOAT_EQ(s.p95, 1.9f);     // the 95th value
  EXPECT_DOUBLE_EQ(s.fraction_above_1, 0.5);
  v.push_back(std::numeric_limits<float>::infinity());
  EXPECT_EQ(density_stats(v).pixels, 101u);
  EXPECT_EQ(density_stats(std::vector<float>{kNaN}).pixels, 0u);
}

}  // namespace
}  // namespace shadow::oracle
