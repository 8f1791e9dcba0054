// The virtual clipmap's geometry (engine/light/virtual_levels.*): levels double, windows cover
// their level and move in whole pages, a page's texels are the same in every window that holds
// it, and the depth range is the scene's whatever the camera.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/light/virtual_levels.hpp"

namespace shadow {
namespace {

constexpr uint32_t kTexels = 2048;  // 16 x 16 pages a level

Light sun() {
  Light l;
  l.direction = {0.3f, -1.0f, 0.2f};
  return l;
}

Bounds street() {
  Bounds b;
  b.extend(glm::dvec3(-800, 0, -20));
  b.extend(glm::dvec3(800, 40, 20));
  return b;
}

glm::dvec3 ndc(const ClipmapLevel& level, const glm::dvec3& p) {
  const glm::dvec4 c = level.setup.world_to_ndc * glm::dvec4(p, 1.0);
  return glm::dvec3(c) / c.w;
}

TEST(VirtualLevels, LevelsDoubleAndEachWindowIsItsLevelAcross) {
  const VirtualLevels c = directional_clipmap(sun(), {3, 1.7, -2}, street(), kTexels, 2, 9);
  ASSERT_EQ(c.levels.size(), 8u);
  for (const ClipmapLevel& l : c.levels) {
    SCOPED_TRACE(l.level);
    EXPECT_EQ(clipmap_texel(l.level, kTexels) * kTexels, std::ldexp(1.0, l.level));
    // Two points a level apart along light-space x land a whole window apart in NDC.
    const glm::dmat4 to_world = glm::inverse(c.view);
    const glm::dvec3 a(to_world * glm::dvec4(0, 0, -10, 1));
    const glm::dvec3 b(to_world * glm::dvec4(std::ldexp(1.0, l.level), 0, -10, 1));
    EXPECT_NEAR(ndc(l, b).x - ndc(l, a).x, 1.0, 1e-9);
    // And along v: texture rows grow with v, as the pages' rows do (virtual_pages.cl).
    const glm::dvec3 v(to_world * glm::dvec4(0, std::ldexp(1.0, l.level), -10, 1));
    EXPECT_NEAR(ndc(l, v).y - ndc(l, a).y, 1.0, 1e-9);
    EXPECT_EQ(l.first_page, glm::floor(l.first_page));
  }
}

TEST(VirtualLevels, WindowsMoveInWholePagesAndPagesKeepTheirTexels) {
  const glm::dvec3 eye(3, 1.7, -2);
  const VirtualLevels before = directional_clipmap(sun(), eye, street(), kTexels, 4, 6);
  const glm::dmat4 to_world = glm::inverse(before.view);
  for (size_t i = 0; i < before.levels.size(); ++i) {
    const int level = before.levels[i].level;
    SCOPED_TRACE(level);
    const double page = clipmap_texel(level, kTexels) * kPageTexels;
    // Where in its page the camera is: a move that stays inside the page keeps the window.
    const glm::dvec2 at(before.view * glm::dvec4(eye, 1.0));
    const glm::dvec2 into = at / page - glm::floor(at / page);
    const glm::dvec3 stay(to_world * glm::dvec4(at.x + (0.9 - into.x) * page, at.y, -5, 1));
    const VirtualLevels inside = directional_clipmap(sun(), stay, street(), kTexels, 4, 6);
    EXPECT_EQ(inside.levels[i].first_page, before.levels[i].first_page);
    EXPECT_EQ(inside.levels[i].setup.world_to_ndc, before.levels[i].setup.world_to_ndc);
    // Some pages on: the window moves by whole quarters of itself, keeping the camera's page
    // in its middle quarter, and a point in both windows sits on the same texel of the same
    // page.
    const double pages = kTexels / kPageTexels, step = pages / 4;
    for (double on : {0.0, 1.5, 3.5, 9.5}) {
      const glm::dvec3 moved(to_world * glm::dvec4(at.x + on * page, at.y, -5, 1));
      const VirtualLevels after = directional_clipmap(sun(), moved, street(), kTexels, 4, 6);
      const double shift = after.levels[i].first_page.x - before.levels[i].first_page.x;
      EXPECT_EQ(shift, std::round(shift / step) * step) << on;
      const double camera_page =
          std::floor((at.x + on * page) / page) - after.levels[i].first_page.x;
      EXPECT_GE(camera_page, pages / 2 - step / 2) << on;
      EXPECT_LT(camera_page, pages / 2 + step / 2) << on;
      const glm::dvec3 p(to_world * glm::dvec4(at.x + 2.3 * page, at.y + 0.4 * page, -7, 1));
      const double t0 = ndc(before.levels[i], p).x * kTexels,
                   t1 = ndc(after.levels[i], p).x * kTexels;
      EXPECT_NEAR(t0 - t1, shift * kPageTexels, 1e-6);
    }
  }
}

TEST(VirtualLevels, DepthIsTheScenesAlongTheLightWhateverTheCamera) {
  const Bounds scene = street();
  const VirtualLevels a = directional_clipmap(sun(), {0, 2, 0}, scene, kTexels, 3, 3);
  const VirtualLevels b = directional_clipmap(sun(), {700, 2, 10}, scene, kTexels, 3, 3);
  EXPECT_EQ(a.depth, b.depth);
  EXPECT_EQ(a.depth.kind, MapDepth::kOrthographic);
  for (const glm::dvec3& corner : scene.corners()) {
    const double z = ndc(a.levels[0], corner).z;
    EXPECT_GT(z, 0.0);
    EXPECT_LT(z, 1.0);
  }
}

TEST(VirtualLevels, APixelReadsTheCoarsestLevelAtLeastAsFineAsItsFootprint) {
  const double texel5 = clipmap_texel(5, kTexels);
  EXPECT_EQ(clipmap_level(texel5, 0, kTexels), 5);
  EXPECT_EQ(clipmap_level(texel5 * 1.9, 0, kTexels), 5);
  EXPECT_EQ(clipmap_level(texel5 * 2, 0, kTexels), 6);
  EXPECT_EQ(clipmap_level(texel5 * 0.99, 0, kTexels), 4);
  EXPECT_EQ(clipmap_level(texel5, -1, kTexels), 4);  // a finer bias: a finer level
  EXPECT_EQ(clipmap_level(texel5, 0.5, kTexels), 5);
  EXPECT_EQ(clipmap_level(texel5, 1, kTexels), 6);
}

}  // namespace
}  // namespace shadow
