// The cube-face fit (engine/light/cube_fit.hpp): which faces a point light needs for a table of
// light positions, and the guard band's geometry. Pure math.
#include <gtest/gtest.h>

#include "engine/light/cube_fit.hpp"

namespace shadow {
namespace {

Bounds box(glm::dvec3 lo, glm::dvec3 hi) {
  Bounds b;
  b.extend(lo);
  b.extend(hi);
  return b;
}

// A 20 x 20 m floor (receives, does not cast) and a 1 m box floating 1..2 m over its centre
// (casts and receives), seen from (0, 8, 12).
std::vector<InstanceBounds> floor_and_box() {
  return {{box({-10, 0, -10}, {10, 0, 10}), false, true},
          {box({-0.5, 1, -0.5}, {0.5, 2, 0.5}), true, true}};
}

Camera camera() {
  Camera c;
  c.eye = {0, 8, 12};
  c.target = {0, 0, 0};
  c.far = 100;
  return c;
}

Light point(glm::vec3 p) {
  Light l;
  l.type = LightType::kPoint;
  l.position = p;
  return l;
}

std::string rendered(const CubeFit& fit) {
  std::string out;
  for (int k = 0; k < 6; ++k)
    if (fit.faces[k].rendered) out += std::string(out.empty() ? "" : " ") + kCubeFaceNames[k];
  return out;
}

TEST(CubeFit, CubeFaceIsTheMajorAxis) {
  EXPECT_EQ(cube_face({2, 1, -1}), 0);
  EXPECT_EQ(cube_face({-2, 1, -1}), 1);
  EXPECT_EQ(cube_face({0.1, 3, -1}), 2);
  EXPECT_EQ(cube_face({0.1, -3, -1}), 3);
  EXPECT_EQ(cube_face({0.1, 0.2, 0.3}), 4);
  EXPECT_EQ(cube_face({0.1, 0.2, -0.3}), 5);
  EXPECT_EQ(cube_face({1, 1, 1}), 0);  // ties go to the earlier face
  EXPECT_EQ(cube_face({0, -1, 1}), 3);
  EXPECT_EQ(cube_face({-1, 0, 1}), 1);
}

// Only faces that can hold a caster of a visible receiver are rendered.
TEST(CubeFit, RendersOnlyTheFacesWithCastersOfVisibleReceivers) {
  struct Row {
    glm::vec3 light;
    const char* faces;
  };
  for (const Row& row : {Row{{0, 4, 0}, "-y"},     // above the box: it shadows the floor below
                         Row{{3, 1.5f, 0}, "-x"},  // beside it: only towards the box
                         Row{{0, 1.5f, 3}, "-z"},  // in front of it
                         // Under it: box-level and conservative, the box's lower corners reach
                         // into the side faces' frusta (the floor there is out of its reach).
                         Row{{0, 0.5f, 0}, "+x -x +y +z -z"}}) {
    const CubeFit fit = fit_cube(point(row.light), camera(), floor_and_box(), 1024, 1, 0.5);
    EXPECT_EQ(rendered(fit), row.faces)
        << "light at " << row.light.x << " " << row.light.y << " " << row.light.z;
  }
  // Nothing casts: no face.
  std::vector<InstanceBounds> no_casters = floor_and_box();
  no_casters[1].casts = false;
  const CubeFit none = fit_cube(point({0, 4, 0}), camera(), no_casters, 1024, 1, 0.5);
  EXPECT_EQ(rendered(none), "");
  EXPECT_EQ(none.faces[3].reason, "no caster between the light and the 2 visible receiver(s)");
  EXPECT_EQ(none.faces[2].reason, "no visible receiver");
  // Inside a closed room that casts: every face.
  std::vector<InstanceBounds> room = floor_and_box();
  room.push_back({box({-6, 0, -6}, {6, 4, 6}), true, true});
  const CubeFit all = fit_cube(point({0, 3, 0}), camera(), room, 1024, 1, 0.5);
  EXPECT_EQ(rendered(all), "+x -x +y -y +z -z");
  EXPECT_EQ(all.faces[0].reason, "1 caster(s) in front of 2 visible receiver(s)");
}

// MAP_FIT_SCENE: the faces serve every receiver, whatever the camera sees.
TEST(CubeFit, SceneFitIgnoresTheCamera) {
  Camera away = camera();
  away.target = {0, 20, 40};  // nothing in view
  const CubeFit by_view = fit_cube(point({0, 4, 0}), away, floor_and_box(), 1024, 1, 0.5);
  EXPECT_EQ(rendered(by_view), "");
  const CubeFit by_scene =
      fit_cube(point({0, 4, 0}), away, floor_and_box(), 1024, 1, 0.5, MapFit::kScene);
  EXPECT_EQ(rendered(by_scene), "-y");
  EXPECT_EQ(by_scene.faces[3].reason, "1 caster(s) in front of 2 receiver(s)");
  EXPECT_EQ(by_scene.faces[2].reason, "no receiver");
  // The side faces reach the floor, but no caster lies between.
  EXPECT_EQ(by_scene.faces[0].reason, "no caster between the light and the 1 receiver(s)");
}

// The 90-degree core of each face spans texels [guard, size - guard]; neighbouring faces meet
// on its edge, and the near plane stays below every caster.
TEST(CubeFit, GuardBandAndDepthRange) {
  std::vector<InstanceBounds> room = floor_and_box();
  room.push_back({box({-6, 0, -6}, {6, 4, 6}), true, true});
  const glm::dvec3 light(0.5, 3, -0.25);
  const uint32_t size = 512, guard = 4;
  const CubeFit fit = fit_cube(point(glm::vec3(light)), camera(), room, size, guard, 0.4);
  const double lo = double(guard) / size, hi = 1.0 - lo;
  for (int k = 0; k < 6; ++k) {
    ASSERT_TRUE(fit.faces[k].rendered) << k;
    EXPECT_EQ(fit.faces[k].setup.faces.owned, 1u << k);
    const glm::dmat4& m = fit.faces[k].setup.world_to_ndc;
    // Directions on the core's corners and edges, and inside it.
    for (double a : {-1.0, -0.3, 0.0, 0.7, 1.0})
      for (double b : {-1.0, 0.2, 1.0}) {
        glm::dvec3 d(0.0);
        d[k / 2] = (k % 2) ? -1.0 : 1.0;
        d[(k / 2 + 1) % 3] = a;
        d[(k / 2 + 2) % 3] = b;
        const double t = 0.5 * (fit.faces[k].near + fit.faces[k].far);
        const glm::dvec4 c = m * glm::dvec4(light + t * d, 1.0);
        const glm::dvec2 uv = glm::dvec2(c) / c.w;
        double edge = 1.0;  // distance of uv to the core's outline
        for (int i = 0; i < 2; ++i) {
          EXPECT_GE(uv[i], lo - 1e-12) << k;
          EXPECT_LE(uv[i], hi + 1e-12) << k;
          edge = std::min({edge, std::abs(uv[i] - lo), std::abs(uv[i] - hi)});
        }
        if (std::abs(a) == 1.0 || std::abs(b) == 1.0) {
          EXPECT_LT(edge, 1e-12) << k;
        }
        EXPECT_GT(c.z / c.w, 0.0);
        EXPECT_LT(c.z / c.w, 1.0);
      }
    // The light-distance bound: 0.4 m from the light at the worst angle of the face.
    EXPECT_LE(fit.faces[k].near, 0.4 / std::sqrt(3.0));
    EXPECT_GT(fit.faces[k].near, 0.99 * 0.4 / std::sqrt(3.0) * (size - 2.0 * guard) / size);
  }
}

// A receiver box that holds the whole camera frustum (terrain or a city block as one mesh) has
// no surface in view: its part in view is the frustum itself, so faces are still rendered.
TEST(CubeFit, AReceiverBoxAroundTheWholeViewStillReceives) {
  const std::vector<InstanceBounds> block = {
      {box({-500, -100, -500}, {500, 100, 500}), false, true},
      {box({-0.5, 1, -0.5}, {0.5, 2, 0.5}), true, false}};
  Camera c = camera();
  c.far = 30;  // the whole frustum inside the block's box
  const CubeFit fit = fit_cube(point({0, 4, 0}), c, block, 1024, 1, 0.5);
  EXPECT_EQ(rendered(fit), "-y");
  EXPECT_GT(fit.faces[3].far, 4.0);  // down to the frustum's far corners below the light
}

}  // namespace
}  // namespace shadow
