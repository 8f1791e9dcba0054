// Attached shadows: a receiver whose seen side faces away from the light gets no light under any
// filter (PRODUCT_VISIBILITY's definition; edge-on sides too: pcf_test.cpp), even an open plane
// whose map depth equals its own, which the depth test alone would light. Closed form: the occluder
// scene's ground and square seen from above under lights from below are dark everywhere; a ground
// that receives no shadows stays lit; and under a sun near the horizon the soft filters give the
// share of its disk above the ground's horizon.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/glm.hpp>

#include "occluder_scene.hpp"

namespace shadow {
namespace {

struct Counts {
  size_t seen = 0, dark = 0, lit = 0;
};

Counts count(const RenderRequest& r) {
  const RenderResult res = testing::engine().render(r);
  Counts c;
  for (float v : res.textures.at(0).data) {
    if (std::isnan(v)) continue;
    ++c.seen;
    c.dark += v == 0.0f;
    c.lit += v == 1.0f;
  }
  return c;
}

// Each light below the ground (directional travelling up, spot and point beneath it).
std::vector<Light> lights_from_below() {
  Light sun;
  sun.direction = {0.3f, 1.0f, 0.2f};
  sun.size = 1.0f;  // degrees: PCSS's search needs a size
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0.5f, -6.0f, 0.5f};
  spot.direction = {0.0f, 1.0f, 0.0f};
  spot.cone_angle_deg = 170.0f;
  spot.size = 0.2f;
  Light point = spot;
  point.type = LightType::kPoint;
  return {sun, spot, point};
}

TEST(AttachedShadow, ASeenSideFacingAwayFromTheLightIsDarkUnderEveryFilter) {
  for (const Light& light : lights_from_below()) {
    for (FilterKind filter :
         {FilterKind::kHard, FilterKind::kPcf2x2, FilterKind::kPoisson, FilterKind::kPcss,
          FilterKind::kCsm, FilterKind::kPcssCsm, FilterKind::kBlur}) {
      // CSM and PSM-style filters need a single map: a point light's cube takes the others.
      if (light.type == LightType::kPoint &&
          (filter == FilterKind::kCsm || filter == FilterKind::kPcssCsm ||
           filter == FilterKind::kPcss || filter == FilterKind::kBlur))
        continue;
      RenderRequest r = testing::occluder_request();
      r.lights = {light};
      r.products = {Product::kVisibility};
      r.filter.kind = filter;
      if (filter == FilterKind::kBlur) {  // the ground is the blurred class
        auto scene = std::make_shared<Scene>(*r.scene);
        scene->instances[0].receiver_class = 1;
        r.scene = scene;
      }
      const Counts c = count(r);
      const std::string what =
          "light " + std::to_string(int(light.type)) + ", filter " + std::to_string(int(filter));
      EXPECT_GT(c.seen, 50000u) << what;
      EXPECT_EQ(c.dark, c.seen) << what;
    }
    // A ground that receives no shadows is lit whichever way it faces.
    RenderRequest r = testing::occluder_request();
    r.lights = {light};
    r.products = {Product::kVisibility};
    auto scene = std::make_shared<Scene>(*r.scene);
    scene->instances[0].receives_shadows = false;
    r.scene = scene;
    const Counts c = count(r);
    EXPECT_GT(c.lit, 50000u) << int(light.type);
  }
}

// A sun of 2 degrees (angular radius 1) at elevations around the horizon, nothing casting: the
// soft filters find no blocker, so what they give is the share of the sun's disk above the
// horizontal receivers, the disk's segment in closed form (as the area-light oracle's samples
// count it): t = tan(elevation) / tan(1 degree), 1 - (acos t - t sqrt(1 - t^2)) / pi.
TEST(AttachedShadow, SoftFiltersGiveTheShareOfTheDiskAboveTheHorizon) {
  const double radius = glm::radians(1.0);
  for (double elevation_deg : {-1.5, -0.9, -0.5, 0.0, 0.3, 0.8, 1.5}) {
    const double e = glm::radians(elevation_deg);
    const double t = std::clamp(std::tan(e) / std::tan(radius), -1.0, 1.0);
    const double want = 1.0 - (std::acos(t) - t * std::sqrt(1.0 - t * t)) / M_PI;
    // Not blur: its class receivers are drawn into its map, so a grazing sun shadows the ground
    // with itself there.
    for (FilterKind filter : {FilterKind::kPcss, FilterKind::kCsm, FilterKind::kPcssCsm}) {
      RenderRequest r = testing::occluder_request();
      r.lights[0].direction = {float(-std::cos(e)), float(-std::sin(e)), 0.0f};
      r.lights[0].size = 2.0f;
      r.products = {Product::kVisibility};
      r.filter.kind = filter;
      auto scene = std::make_shared<Scene>(*r.scene);
      for (Instance& i : scene->instances) i.casts_shadows = false;
      r.scene = scene;
      const RenderResult res = testing::engine().render(r);
      size_t seen = 0;
      double worst = 0;
      for (float v : res.textures.at(0).data) {
        if (std::isnan(v)) continue;
        ++seen;
        worst = std::max(worst, std::abs(v - want));
      }
      const std::string what = "elevation " + std::to_string(elevation_deg) + " deg, filter " +
                               std::to_string(int(filter));
      EXPECT_GT(seen, 50000u) << what;
      EXPECT_LT(worst, 2e-5) << what << ": want " << want;
    }
  }
}

}  // namespace
}  // namespace shadow
