// Attached shadows: a receiver whose seen side faces away from the light gets no light under any
// filter (PRODUCT_VISIBILITY's definition; edge-on sides too: pcf_test.cpp), even an open plane
// whose map depth equals its own, which the depth test alone would light. Closed form: the occluder
// scene's ground and square seen from above under lights from below are dark everywhere; a ground
// that receives no shadows stays lit.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "occluder_scene.hpp"

namespace shadow {
namespace {

struct Counts {
  size_t seen = 0, dark = 0, lit = 0;
};

Counts count(const RenderRequest& r) {
  const RenderResult res = testing::shared_engine().render(r);
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

}  // namespace
}  // namespace shadow
