#include "scenes/shapes.hpp"

#include <cmath>

namespace shadow::scenes {
namespace {

constexpr float kPi = 3.14159265358979f;

uint32_t add_vertex(Mesh& m, glm::vec3 p, glm::vec3 n, glm::vec2 uv) {
  m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
  m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
  m.uvs.insert(m.uvs.end(), {uv.x, uv.y});
  return static_cast<uint32_t>(m.vertex_count() - 1);
}

// Quad a-b-c-d, counter-clockwise seen from the side its normal points to.
void add_quad(Mesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
}

}  // namespace

Mesh make_grid(float extent, int cells) {
  Mesh m;
  const float h = extent / 2;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) {
      const float u = static_cast<float>(i) / cells, v = static_cast<float>(j) / cells;
      add_vertex(m, {-h + u * extent, 0, -h + v * extent}, {0, 1, 0}, {u, v});
    }
  const auto at = [&](int i, int j) { return static_cast<uint32_t>(j * (cells + 1) + i); };
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i)  // +z then +x is counter-clockwise seen from +y
      add_quad(m, at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
  return m;
}

Mesh make_box() {
  Mesh m;
  const glm::vec3 normals[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  for (const glm::vec3& n : normals) {
    // Two tangents with t × b = n, so corners n/2 ± t/2 ± b/2 run counter-clockwise around n.
    const glm::vec3 t = std::abs(n.y) > 0 ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
    const glm::vec3 b = glm::cross(n, t);
    const glm::vec3 c = n * 0.5f;
    const uint32_t a0 = add_vertex(m, c - 0.5f * t - 0.5f * b, n, {0, 0});
    const uint32_t a1 = add_vertex(m, c + 0.5f * t - 0.5f * b, n, {1, 0});
    const uint32_t a2 = add_vertex(m, c + 0.5f * t + 0.5f * b, n, {1, 1});
    const uint32_t a3 = add_vertex(m, c - 0.5f * t + 0.5f * b, n, {0, 1});
    add_quad(m, a0, a1, a2, a3);
  }
  return m;
}

Mesh make_sphere(int slices, int stacks) {
  Mesh m;
  for (int j = 0; j <= stacks; ++j) {
    const float v = static_cast<float>(j) / stacks, theta = v * kPi;  // from the north pole
    for (int i = 0; i <= slices; ++i) {
      const float u = static_cast<float>(i) / slices, phi = u * 2 * kPi;
      const glm::vec3 p(std::sin(theta) * std::cos(phi), std::cos(theta),
                        -std::sin(theta) * std::sin(phi));
      add_vertex(m, p, p, {u, v});
    }
  }
  const auto at = [&](int i, int j) { return static_cast<uint32_t>(j * (slices + 1) + i); };
  for (int j = 0; j < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      // Skip the degenerate triangle of each polar quad.
      if (j > 0) m.indices.insert(m.indices.end(), {at(i, j), at(i, j + 1), at(i + 1, j)});
      if (j < stacks - 1)
        m.indices.insert(m.indices.end(), {at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)});
    }
  return m;
}

Mesh make_cylinder(int segments) {
  Mesh m;
  const auto rim = [&](int i) {
    const float phi = 2 * kPi * i / segments;
    return glm::vec3(std::cos(phi), 0, -std::sin(phi));  // counter-clockwise seen from +y
  };
  for (int i = 0; i < segments; ++i) {
    const glm::vec3 r0 = rim(i), r1 = rim(i + 1);
    const float u0 = static_cast<float>(i) / segments, u1 = static_cast<float>(i + 1) / segments;
    const uint32_t a = add_vertex(m, r0, r0, {u0, 0});
    const uint32_t b = add_vertex(m, r1, r1, {u1, 0});
    const uint32_t c = add_vertex(m, r1 + glm::vec3(0, 1, 0), r1, {u1, 1});
    const uint32_t d = add_vertex(m, r0 + glm::vec3(0, 1, 0), r0, {u0, 1});
    add_quad(m, a, b, c, d);
  }
  for (float y : {0.0f, 1.0f}) {
    const glm::vec3 n(0, y > 0 ? 1 : -1, 0);
    const uint32_t centre = add_vertex(m, {0, y, 0}, n, {0.5f, 0.5f});
    for (int i = 0; i < segments; ++i) {
      const glm::vec3 r0 = rim(i) + glm::vec3(0, y, 0), r1 = rim(i + 1) + glm::vec3(0, y, 0);
      const uint32_t a = add_vertex(m, r0, n, {0.5f + r0.x / 2, 0.5f + r0.z / 2});
      const uint32_t b = add_vertex(m, r1, n, {0.5f + r1.x / 2, 0.5f + r1.z / 2});
      if (y > 0)
        m.indices.insert(m.indices.end(), {centre, a, b});
      else
        m.indices.insert(m.indices.end(), {centre, b, a});
    }
  }
  return m;
}

}  // namespace shadow::scenes
