#include "oracle/standard_scenes.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

#include "oracle/scenes.hpp"

namespace shadow::scenes {
namespace {

Camera camera(glm::vec3 eye, glm::vec3 target, float near, float far, float fov = 60.0f) {
  Camera c;
  c.eye = eye;
  c.target = target;
  c.fov_deg = fov;
  c.width = 640;
  c.height = 360;
  c.near = near;
  c.far = far;
  return c;
}

Light sun(glm::vec3 direction, float diameter_deg = 0.5f) {
  Light l;
  l.type = LightType::kDirectional;
  l.direction = glm::normalize(direction);
  l.size = diameter_deg;
  return l;
}

Light spot(glm::vec3 position, glm::vec3 target, float cone_deg, float radius) {
  Light l;
  l.type = LightType::kSpot;
  l.position = position;
  l.direction = glm::normalize(target - position);
  l.cone_angle_deg = cone_deg;
  l.size = radius;
  return l;
}

// A sun travelling almost along the camera's view direction, tilted `off_deg` towards -y so it
// still reaches the ground: `sign` +1 puts it behind the camera, -1 in front (facing it).
Light sun_along_view(const Camera& c, float sign, float off_deg, float diameter_deg = 0.5f) {
  glm::vec3 view = glm::normalize(c.target - c.eye);
  glm::vec3 d = sign * view;
  d.y = -std::abs(d.y) - std::tan(glm::radians(off_deg));
  return sun(d, diameter_deg);
}

// A sun `elevation_deg` above the horizon from azimuth angle `azimuth_deg` (about +y).
Light sun_elevation(float elevation_deg, float azimuth_deg, float diameter_deg = 0.5f) {
  const float e = glm::radians(elevation_deg), a = glm::radians(azimuth_deg);
  return sun({-std::cos(e) * std::cos(a), -std::sin(e), -std::cos(e) * std::sin(a)}, diameter_deg);
}

}  // namespace

StandardScene chess() {
  auto s = std::make_shared<Scene>();
  // Board: 8 x 8 squares of 1 m, each its own box top so squares are separate casters.
  add(*s, box_mesh(), trs({0, -0.1f, 0}, 0, {0, 1, 0}, {9, 0.2f, 9}));
  add(*s, grid_mesh(1), trs({0, -0.2f, 0}, 0, {0, 1, 0}, {60, 1, 60}));  // table
  for (int side = 0; side < 2; ++side) {
    const float row_z = side ? -3.5f : 3.5f, pawn_z = side ? -2.5f : 2.5f;
    for (int f = 0; f < 8; ++f) {
      const float x = -3.5f + f;
      // Pawn: a stem and a head.
      add(*s, prism_mesh(16), trs({x, 0, pawn_z}, 0, {0, 1, 0}, {0.5f, 0.45f, 0.5f}));
      add(*s, prism_mesh(12), trs({x, 0.45f, pawn_z}, 0, {0, 1, 0}, {0.3f, 0.25f, 0.3f}));
      // Back row: heights rook 0.8, knight 0.9, bishop 1.0, queen 1.2, king 1.3.
      const float h[8] = {0.8f, 0.9f, 1.0f, 1.2f, 1.3f, 1.0f, 0.9f, 0.8f};
      add(*s, prism_mesh(20), trs({x, 0, row_z}, 0, {0, 1, 0}, {0.6f, h[f], 0.6f}));
      add(*s, box_mesh(), trs({x, h[f] + 0.1f, row_z}, 45, {0, 1, 0}, {0.3f, 0.2f, 0.3f}));
    }
  }
  StandardScene out{"chess", s, {}};
  const Camera player = camera({0, 7, 10}, {0, 0, 0}, 0.1f, 100.0f);
  out.views.push_back({"overview", player, spot({3, 9, 4}, {0, 0, 0}, 70, 0.15f)});
  // The spot sits just behind the player's eye, shining where the player looks.
  out.views.push_back(
      {"light_behind_camera", player, spot({0.5f, 8.5f, 12.5f}, {0, 0, 0}, 60, 0.15f)});
  // The spot faces the player from across the board.
  out.views.push_back(
      {"light_facing_camera", player, spot({0.5f, 7.5f, -11}, {0, 0, 1}, 70, 0.15f)});
  out.views.push_back({"grazing", player, spot({-14, 1.2f, 1}, {0, 0, 0}, 60, 0.1f)});
  return out;
}

StandardScene street() {
  auto s = std::make_shared<Scene>();
  const float length = 1500.0f;
  add(*s, grid_mesh(16), trs({0, 0, -length / 2 + 50}, 0, {0, 1, 0}, {120, 1, length + 100}));
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> height(8, 40), depth(12, 24), gap(0, 4);
  for (int side = -1; side <= 1; side += 2) {
    for (float z = 20; z > -length;) {
      const float w = depth(rng), h = height(rng);
      add(*s, box_mesh(), trs({side * (10 + 8.0f), h / 2, z - w / 2}, 0, {0, 1, 0}, {16, h, w}));
      z -= w + gap(rng);
    }
  }
  for (float z = 10; z > -length; z -= 30) {  // lamp poles on both kerbs
    for (int side = -1; side <= 1; side += 2)
      add(*s, prism_mesh(8), trs({side * 7.5f, 0, z}, 0, {0, 1, 0}, {0.2f, 6, 0.2f}));
  }
  StandardScene out{"street", s, {}};
  const Camera eye = camera({1.5f, 1.7f, 0}, {1.5f, 1.7f, -100}, 0.1f, 2000.0f);
  out.views.push_back({"overview", eye, sun_elevation(35, 60)});
  out.views.push_back({"light_behind_camera", eye, sun_along_view(eye, 1, 20)});
  out.views.push_back({"light_facing_camera", eye, sun_along_view(eye, -1, 20)});
  out.views.push_back({"grazing", eye, sun_elevation(4, 80)});
  return out;
}

StandardScene forest() {
  auto s = std::make_shared<Scene>();
  // Terrain: a 96 x 96 grid with gentle hills, 200 m across.
  Mesh terrain = grid_mesh(96);
  auto ground = [](float x, float z) {
    return 1.5f * std::sin(0.05f * x) * std::cos(0.07f * z) + 0.6f * std::sin(0.13f * x + 0.2f * z);
  };
  for (size_t v = 0; v < terrain.vertex_count(); ++v) {
    float& x = terrain.positions[3 * v];
    float& z = terrain.positions[3 * v + 2];
    x *= 200.0f;
    z *= 200.0f;
    terrain.positions[3 * v + 1] = ground(x, z);
  }
  add(*s, std::move(terrain), glm::mat4(1.0f));
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> pos(-90, 90), height(8, 16), radius(0.1f, 0.25f);
  for (int t = 0; t < 600; ++t) {
    const float x = pos(rng), z = pos(rng), r = radius(rng);
    add(*s, prism_mesh(7),
        trs({x, ground(x, z) - 0.3f, z}, 0, {0, 1, 0}, {2 * r, height(rng), 2 * r}));
  }
  StandardScene out{"forest", s, {}};
  const Camera walker = camera({0, 1.7f + 0.0f, 60}, {0, 1.0f, 0}, 0.1f, 400.0f);
  const Camera above = camera({-40, 45, 70}, {0, 0, 0}, 0.5f, 400.0f);
  out.views.push_back({"overview", above, sun_elevation(50, 30)});
  out.views.push_back({"walker", walker, sun_elevation(40, 130)});
  out.views.push_back({"light_behind_camera", walker, sun_along_view(walker, 1, 25)});
  out.views.push_back({"grazing", walker, sun_elevation(6, 200)});
  return out;
}

StandardScene resting() {
  auto s = std::make_shared<Scene>();
  add(*s, grid_mesh(4), trs({0, 0, 0}, 0, {0, 1, 0}, {30, 1, 30}));
  add(*s, box_mesh(), trs({-2, 0.5f, 0}, 20, {0, 1, 0}, {1, 1, 1}));
  add(*s, box_mesh(), trs({0.5f, 0.02f, 0.5f}, 0, {0, 1, 0}, {2, 0.04f, 1.2f}));  // thin slab
  add(*s, box_mesh(), trs({2.5f, 1.0f, -1}, 0, {0, 1, 0}, {0.4f, 2.0f, 0.4f}));   // column
  add(*s, box_mesh(), trs({0, 0.25f, -2.5f}, 45, {0, 1, 0}, {0.5f, 0.5f, 0.5f}));
  // A box leaning on the floor at 30 degrees, touching along an edge.
  add(*s, box_mesh(), trs({-0.5f, 0.45f, 2.5f}, 30, {0, 0, 1}, {1.2f, 0.2f, 0.8f}));
  StandardScene out{"resting", s, {}};
  const Camera close = camera({0, 3, 7}, {0, 0.2f, 0}, 0.1f, 60.0f, 50.0f);
  out.views.push_back({"overview", close, sun_elevation(45, 40)});
  out.views.push_back({"light_behind_camera", close, sun_along_view(close, 1, 5)});
  out.views.push_back({"light_facing_camera", close, sun_along_view(close, -1, 10)});
  out.views.push_back({"grazing", close, sun_elevation(8, 20)});
  return out;
}

StandardScene heights() {
  auto s = std::make_shared<Scene>();
  add(*s, grid_mesh(4), trs({0, 0, 0}, 0, {0, 1, 0}, {40, 1, 40}));
  const float h[6] = {0.05f, 0.25f, 0.5f, 1.0f, 2.0f, 4.0f};
  for (int k = 0; k < 6; ++k) {
    const float x = -7.5f + 3.0f * k;
    add(*s, box_mesh(), trs({x, h[k] + 0.05f, 0}, 0, {0, 1, 0}, {1.0f, 0.1f, 1.0f}));  // plate
    add(*s, prism_mesh(8), trs({x, 0, 3}, 0, {0, 1, 0}, {0.1f, h[k] + 0.5f, 0.1f}));   // stick
  }
  StandardScene out{"heights", s, {}};
  const Camera above = camera({0, 14, 12}, {0, 0, 1}, 0.1f, 100.0f, 50.0f);
  out.views.push_back({"overview", above, sun_elevation(60, 70, 2.0f)});
  out.views.push_back({"light_behind_camera", above, sun_along_view(above, 1, 5, 2.0f)});
  out.views.push_back({"grazing", above, sun_elevation(10, 90, 2.0f)});
  return out;
}

Light point(glm::vec3 position, float radius) {
  Light l;
  l.type = LightType::kPoint;
  l.position = position;
  l.size = radius;
  return l;
}

StandardScene room() {
  auto s = std::make_shared<Scene>();
  add(*s, box_mesh(), trs({0, 2, 0}, 0, {0, 1, 0}, {12, 4, 12}));  // walls, floor and ceiling
  add(*s, box_mesh(), trs({-1.5f, 0.4f, -1}, 20, {0, 1, 0}, {2, 0.8f, 1}));    // table
  add(*s, prism_mesh(12), trs({2, 0, -2.5f}, 0, {0, 1, 0}, {0.2f, 3, 0.2f}));  // pole
  add(*s, box_mesh(), trs({0.9f, 2.1f, 0.1f}, 35, {1, 0.7f, 0.2f}, {0.3f, 0.3f, 0.3f}));
  add(*s, box_mesh(), trs({-5.5f, 1.5f, 3}, 25, {0, 0, 1}, {0.1f, 3, 2}));  // leaning slab
  StandardScene out{"room", s, {}};
  const Camera corner = camera({5, 2.2f, 5}, {-2, 0.8f, -2}, 0.05f, 30.0f, 85.0f);
  out.views.push_back({"point_centre", corner, point({0.7f, 2.6f, -0.4f}, 0.05f)});
  out.views.push_back({"point_near_wall", corner, point({-5.2f, 3.0f, -4.6f}, 0.05f)});
  out.views.push_back({"point_low", corner, point({-1.0f, 1.2f, 1.5f}, 0.05f)});
  return out;
}

std::vector<StandardScene> standard_scenes() {
  return {chess(), street(), forest(), resting(), heights(), room()};
}

const View& find_view(const StandardScene& scene, const std::string& name) {
  for (const View& v : scene.views)
    if (v.name == name) return v;
  throw std::invalid_argument(scene.name + " has no view " + name);
}

}  // namespace shadow::scenes
