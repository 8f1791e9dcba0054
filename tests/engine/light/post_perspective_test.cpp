// The light in the camera's post-perspective space: every case of the PSM paper (§3), the case
// boundaries without NaN or Inf, and the defining property that the camera's projection maps
// a ray towards the light onto the line towards the post-perspective light.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/post_perspective.hpp"

namespace shadow {
namespace {

// Camera at the origin looking down -z (GL), near 1, far 100.
glm::dmat4 camera() {
  return glm::perspective(glm::radians(60.0), 1.0, 1.0, 100.0) *
         glm::lookAt(glm::dvec3(0), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0));
}

Light directional(glm::vec3 travel) {
  Light l;
  l.direction = travel;
  return l;
}

Light point(glm::vec3 p) {
  Light l;
  l.type = LightType::kPoint;
  l.position = p;
  return l;
}

bool finite(const PostPerspectiveLight& l) {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(l.position[i]) || !std::isfinite(l.direction[i])) return false;
  return std::isfinite(l.homogeneous.w);
}

TEST(PostPerspective, DirectionalFromTheFrontIsAPointOnThePlaneAtInfinity) {
  // Travels towards the camera, i.e. the light is in front of it.
  PostPerspectiveLight l = post_perspective_light(directional({0, -1, 1}), camera());
  EXPECT_EQ(l.kind, PostPerspectiveCase::kPoint);
  EXPECT_NEAR(l.position.z, (100.0 + 1.0) / (100.0 - 1.0), 1e-12);  // (f + n) / (f - n)
  EXPECT_EQ(l.description, "directional from the front: point light");
}

TEST(PostPerspective, DirectionalFromBehindIsInverted) {
  PostPerspectiveLight l = post_perspective_light(directional({0, -1, -1}), camera());
  EXPECT_EQ(l.kind, PostPerspectiveCase::kInvertedPoint);
  EXPECT_NEAR(l.position.z, (100.0 + 1.0) / (100.0 - 1.0), 1e-12);
  EXPECT_EQ(l.description, "directional from behind: inverted point light");
}

TEST(PostPerspective, DirectionalParallelToTheImagePlaneStaysDirectional) {
  PostPerspectiveLight l = post_perspective_light(directional({1, -1, 0}), camera());
  EXPECT_EQ(l.kind, PostPerspectiveCase::kDirectional);
  EXPECT_TRUE(finite(l));
  // Travel keeps its image-plane orientation: +x and -y in NDC.
  EXPECT_GT(l.direction.x, 0.0);
  EXPECT_LT(l.direction.y, 0.0);
  EXPECT_NEAR(l.direction.z, 0.0, 1e-12);
}

TEST(PostPerspective, PointLightsInFrontBehindAndInTheCameraPlane) {
  PostPerspectiveLight front = post_perspective_light(point({1, 2, -10}), camera());
  EXPECT_EQ(front.kind, PostPerspectiveCase::kPoint);
  EXPECT_EQ(front.description, "point from the front: point light");
  PostPerspectiveLight behind = post_perspective_light(point({1, 2, 10}), camera());
  EXPECT_EQ(behind.kind, PostPerspectiveCase::kInvertedPoint);
  PostPerspectiveLight plane = post_perspective_light(point({1, 2, 0}), camera());
  EXPECT_EQ(plane.kind, PostPerspectiveCase::kDirectional);
  EXPECT_EQ(plane.description, "point in the camera plane: directional");
  EXPECT_TRUE(finite(plane));
}

// Exactly on, and a hair either side of, each case boundary: never NaN or Inf.
TEST(PostPerspective, CaseBoundariesStayFinite) {
  for (float eps : {0.0f, 1e-7f, -1e-7f, 1e-3f, -1e-3f}) {
    EXPECT_TRUE(finite(post_perspective_light(directional({1, -1, eps}), camera()))) << eps;
    EXPECT_TRUE(finite(post_perspective_light(point({3, 1, eps}), camera()))) << eps;
  }
  // Along the view direction, both signs, and the light at the eye itself.
  EXPECT_TRUE(finite(post_perspective_light(directional({0, 0, -1}), camera())));
  EXPECT_TRUE(finite(post_perspective_light(directional({0, 0, 1}), camera())));
  PostPerspectiveLight at_eye = post_perspective_light(point({0, 0, 0}), camera());
  EXPECT_TRUE(std::isfinite(at_eye.homogeneous.w));
}

// The projection maps the ray from a point towards the light onto the post-perspective line
// from the projected point towards L (or along L's direction when L is at infinity).
TEST(PostPerspective, RaysTowardsTheLightMapToLinesThroughIt) {
  const glm::dmat4 m = camera();
  auto ndc = [&](glm::dvec3 p) {
    glm::dvec4 c = m * glm::dvec4(p, 1.0);
    return glm::dvec3(c) / c.w;
  };
  const glm::dvec3 x(0.5, -1.0, -8.0);
  struct Case {
    Light light;
    glm::dvec3 towards;  // world direction from x towards the light
  };
  const Case cases[] = {
      {directional({0.3f, -1, 0.5f}), -glm::normalize(glm::dvec3(glm::vec3(0.3f, -1, 0.5f)))},
      {directional({0.3f, -1, -0.5f}), -glm::normalize(glm::dvec3(glm::vec3(0.3f, -1, -0.5f)))},
      {point({2, 5, -4}), glm::normalize(glm::dvec3(2, 5, -4) - x)},
      {point({2, 5, 3}), glm::normalize(glm::dvec3(2, 5, 3) - x)},
  };
  for (const Case& c : cases) {
    PostPerspectiveLight l = post_perspective_light(c.light, m);
    const glm::dvec3 a = ndc(x), b = ndc(x + 0.5 * c.towards);
    const glm::dvec3 to_light = l.position - a;
    // b - a is parallel to L - a.
    EXPECT_LT(glm::length(glm::cross(glm::normalize(b - a), glm::normalize(to_light))), 1e-9)
        << l.description;
  }
}

}  // namespace
}  // namespace shadow
