// Light-space set-up is pure math: tested here without OpenCL.
#include <gtest/gtest.h>

#include "engine/light/light_space.hpp"

namespace shadow {
namespace {

glm::dvec3 to_ndc(const glm::dmat4& m, const glm::dvec3& p) {
  glm::dvec4 c = m * glm::dvec4(p, 1.0);
  return glm::dvec3(c) / c.w;
}

void expect_inside_unit_cube(const glm::dmat4& m, const Bounds& b, const char* what) {
  for (const glm::dvec3& p : b.corners()) {
    glm::dvec3 q = to_ndc(m, p);
    for (int i = 0; i < 3; ++i) {
      EXPECT_GE(q[i], 0.0) << what << " axis " << i;
      EXPECT_LE(q[i], 1.0) << what << " axis " << i;
    }
  }
}

Camera street_camera() {
  Camera c;
  c.eye = {0, 5, 15};
  c.target = {0, 0, 0};
  c.near = 0.1f;
  c.far = 100.0f;
  return c;
}

const Bounds kGround{{-10, -0.1, -10}, {10, 0, 10}};
const Bounds kBox{{-1, 0, -1}, {1, 2, 1}};

TEST(LightSpace, TextureNdcPutsRowZeroAtTheTop) {
  ViewSetup s = camera_setup(street_camera());
  glm::dvec3 centre = to_ndc(s.world_to_ndc, {0, 0, 0});
  EXPECT_NEAR(centre.x, 0.5, 1e-12);
  EXPECT_NEAR(centre.y, 0.5, 1e-12);
  EXPECT_LT(to_ndc(s.world_to_ndc, {0, 1, 0}).y, 0.5);  // above the target: nearer row 0
  EXPECT_GT(to_ndc(s.world_to_ndc, {1, 0, 0}).x, 0.5);  // to the right
  glm::dvec3 eye(0, 5, 15), forward = glm::normalize(-eye);
  EXPECT_NEAR(to_ndc(s.world_to_ndc, eye + 0.1 * forward).z, 0.0, 1e-6);    // near plane -> 0
  EXPECT_NEAR(to_ndc(s.world_to_ndc, eye + 100.0 * forward).z, 1.0, 1e-6);  // far plane -> 1
}

TEST(LightSpace, DirectionalFitContainsReceiversAndTheirCasters) {
  Light sun;
  sun.direction = {-1, -2, -0.5};
  std::vector<InstanceBounds> inst = {{kGround, true, true}, {kBox, true, true}};
  ViewSetup s = fit_uniform_light(sun, street_camera(), inst);
  expect_inside_unit_cube(s.world_to_ndc, kGround, "ground");
  expect_inside_unit_cube(s.world_to_ndc, kBox, "box");
}

TEST(LightSpace, DirectionalFitIgnoresCastersThatCannotShadowTheView) {
  Light sun;
  sun.direction = {0, -1, 0};
  std::vector<InstanceBounds> inst = {{kGround, false, true}, {kBox, true, false}};
  ViewSetup base = fit_uniform_light(sun, street_camera(), inst);
  // Far to the side of every receiver, and high up: it shadows nothing the camera sees.
  inst.push_back({Bounds{{500, 0, 0}, {501, 300, 1}}, true, false});
  ViewSetup with = fit_uniform_light(sun, street_camera(), inst);
  EXPECT_EQ(base.world_to_ndc, with.world_to_ndc);
}

TEST(LightSpace, DirectionalFitNarrowsToTheCastersExtent) {
  Light sun;
  sun.direction = {0, -1, 0};
  std::vector<InstanceBounds> inst = {{kGround, false, true}, {kBox, true, false}};
  ViewSetup s = fit_uniform_light(sun, street_camera(), inst);
  // Straight down, the box's 2 x 2 m footprint fills the map (within the 0.1% slack)...
  EXPECT_NEAR(to_ndc(s.world_to_ndc, {-1, 0, -1}).x, 0.0, 2e-3);
  EXPECT_NEAR(to_ndc(s.world_to_ndc, {1, 0, 1}).x, 1.0, 2e-3);
  // ...while depth still reaches the ground under it.
  EXPECT_LE(to_ndc(s.world_to_ndc, {0, -0.1, 0}).z, 1.0);
  EXPECT_GE(to_ndc(s.world_to_ndc, {0, 2, 0}).z, 0.0);
}

TEST(LightSpace, DirectionalFitKeepsCastersBehindTheCamera) {
  Light sun;
  sun.direction = {0, -1, -1};  // travels away from the camera side
  // Behind and above the camera, between the sun and the visible ground.
  Bounds tower{{-1, 0, 20}, {1, 40, 22}};
  std::vector<InstanceBounds> inst = {{kGround, false, true}, {tower, true, false}};
  ViewSetup s = fit_uniform_light(sun, street_camera(), inst);
  // The tower's shadow reaches z = 22 - 40 = -18 < 10: it shadows the ground, so its near end
  // must be inside the depth range.
  EXPECT_GE(to_ndc(s.world_to_ndc, {0, 40, 21}).z, 0.0);
  // Where the tower's shadow falls, the ground is inside the map.
  expect_inside_unit_cube(s.world_to_ndc, Bounds{{-1, -0.1, -10}, {1, 0, 2}}, "shadowed ground");
}

TEST(LightSpace, ReceiversOutsideTheViewDoNotWidenTheMap) {
  Light sun;
  sun.direction = {0, -1, 0};
  std::vector<InstanceBounds> inst = {{kGround, true, true}};
  ViewSetup base = fit_uniform_light(sun, street_camera(), inst);
  inst.push_back({Bounds{{200, 0, 200}, {210, 1, 210}}, true, true});  // far outside the view
  ViewSetup with = fit_uniform_light(sun, street_camera(), inst);
  EXPECT_EQ(base.world_to_ndc, with.world_to_ndc);
}

TEST(LightSpace, SpotFitContainsEverythingInFront) {
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0, 8, 0};
  spot.direction = {0, -1, 0};
  spot.cone_angle_deg = 120.0f;
  std::vector<InstanceBounds> inst = {{kGround, true, true}, {kBox, true, true}};
  ViewSetup s = fit_uniform_light(spot, street_camera(), inst);
  for (const glm::dvec3& p : kBox.corners()) {
    double z = to_ndc(s.world_to_ndc, p).z;
    EXPECT_GE(z, 0.0);
    EXPECT_LE(z, 1.0);
  }
  EXPECT_NEAR(to_ndc(s.world_to_ndc, {0, 0, 0}).x, 0.5, 1e-9);  // the axis hits the centre
}

// A receiver box reaching behind the light's plane must not drag near to the light: near is
// the nearest caster inside the cone.
TEST(LightSpace, SpotNearIsTheNearestCasterInTheCone) {
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0, 10, 0};
  spot.direction = {0, -1, 0};
  spot.cone_angle_deg = 60.0f;
  Bounds wide{{-50, -0.1, -50}, {50, 20, 50}};  // a receiver spanning the light's plane
  std::vector<InstanceBounds> inst = {{wide, false, true}, {kBox, true, false}};
  ViewSetup s = fit_uniform_light(spot, street_camera(), inst);
  // The box top (y = 2) is 8 below the light: it must sit at NDC depth ~0, not be squeezed
  // against 1 as a near plane of 1e-4 * far would do.
  EXPECT_GE(to_ndc(s.world_to_ndc, {0, 2, 0}).z, 0.0);
  EXPECT_LT(to_ndc(s.world_to_ndc, {0, 2, 0}).z, 0.01);
  EXPECT_LE(to_ndc(s.world_to_ndc, {0, -0.1, 0}).z, 1.0);
}

TEST(LightSpace, VisibilityTestUsesAllSixPlanes) {
  ViewSetup s = camera_setup(street_camera());
  EXPECT_TRUE(may_be_visible(kBox, s.world_to_ndc));
  EXPECT_FALSE(may_be_visible(Bounds{{-1, 0, 30}, {1, 1, 31}}, s.world_to_ndc));      // behind
  EXPECT_FALSE(may_be_visible(Bounds{{-1, 0, -500}, {1, 1, -400}}, s.world_to_ndc));  // past far
  EXPECT_FALSE(may_be_visible(Bounds{{100, 0, 0}, {101, 1, 1}}, s.world_to_ndc));     // right
}

}  // namespace
}  // namespace shadow
