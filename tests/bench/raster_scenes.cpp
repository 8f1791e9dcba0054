#include "raster_scenes.hpp"

#include <cmath>
#include <limits>
#include <random>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "oracle/scenes.hpp"

namespace shadow::bench {
namespace {

// A sun at a moderate angle; the map's orthographic box is the mesh's light-space bounds.
glm::mat4 fit_ortho(const Mesh& mesh, glm::vec3 light_dir) {
  const glm::mat4 view = glm::lookAt(-light_dir, glm::vec3(0), glm::vec3(0, 0, -1));
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    const glm::vec3 p = glm::vec3(view * glm::vec4(glm::make_vec3(&mesh.positions[3 * v]), 1));
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 pad = 1e-3f * (hi - lo);
  lo -= pad;
  hi += pad;
  // glm::ortho's near/far are distances along -z; GL clip -> texture NDC (y down, z 0..1).
  const glm::mat4 proj = glm::ortho(lo.x, hi.x, lo.y, hi.y, -hi.z, -lo.z);
  const glm::mat4 gl_to_tex(0.5f, 0, 0, 0, 0, -0.5f, 0, 0, 0, 0, 0.5f, 0, 0.5f, 0.5f, 0.5f, 1);
  return gl_to_tex * proj * view;
}

void append(Mesh& into, const Mesh& m, const glm::mat4& to_world) {
  const auto base = static_cast<uint32_t>(into.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const glm::vec4 p = to_world * glm::vec4(glm::make_vec3(&m.positions[3 * v]), 1.0f);
    into.positions.insert(into.positions.end(), {p.x, p.y, p.z});
  }
  for (uint32_t i : m.indices) into.indices.push_back(base + i);
}

// Unit sphere, `slices` around and `stacks` from pole to pole: 2 * slices * (stacks - 1)
// triangles (one fan row at each pole, two triangles per quad between).
Mesh unit_sphere(int slices, int stacks) {
  Mesh m;
  m.positions.insert(m.positions.end(), {0, 1, 0});
  for (int j = 1; j < stacks; ++j) {
    const float th = float(M_PI) * j / stacks;
    for (int i = 0; i < slices; ++i) {
      const float ph = 2.0f * float(M_PI) * i / slices;
      m.positions.insert(m.positions.end(),
                         {std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)});
    }
  }
  m.positions.insert(m.positions.end(), {0, -1, 0});
  const auto ring = [&](int j, int i) { return uint32_t(1 + (j - 1) * slices + (i % slices)); };
  const auto bottom = uint32_t(1 + (stacks - 1) * slices);
  for (int i = 0; i < slices; ++i) {
    m.indices.insert(m.indices.end(), {0, ring(1, i + 1), ring(1, i)});
    for (int j = 1; j + 1 < stacks; ++j)
      m.indices.insert(m.indices.end(), {ring(j, i), ring(j, i + 1), ring(j + 1, i + 1), ring(j, i),
                                         ring(j + 1, i + 1), ring(j + 1, i)});
    m.indices.insert(m.indices.end(), {ring(stacks - 1, i), ring(stacks - 1, i + 1), bottom});
  }
  return m;
}

}  // namespace

RasterScene sphere_crowd() {
  RasterScene s;
  const float half = 100.0f;
  s.mesh.positions = {-half, 0, -half, half, 0, -half, half, 0, half, -half, 0, half};
  s.mesh.indices = {0, 2, 1, 0, 3, 2};
  const Mesh sphere = unit_sphere(20, 11);  // 400 triangles
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> radius(0.4f, 1.4f), lift(0.0f, 2.0f), jitter(-0.5f, 0.5f);
  for (int j = 0; j < 50; ++j)
    for (int i = 0; i < 50; ++i) {
      const float r = radius(rng), x = -98.0f + 4.0f * i + jitter(rng),
                  z = -98.0f + 4.0f * j + jitter(rng);
      const glm::mat4 t =
          glm::scale(glm::translate(glm::mat4(1.0f), {x, r + lift(rng), z}), glm::vec3(r));
      append(s.mesh, sphere, t);
    }
  s.world_to_ndc = fit_ortho(s.mesh, glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)));
  return s;
}

RasterScene random_field(size_t count) {
  const scenes::Setup setup = scenes::random_triangles(count, 100.0f, 0.15f);
  RasterScene s;
  for (const Instance& inst : setup.scene.instances)
    append(s.mesh, setup.scene.meshes[inst.mesh], inst.transform);
  s.world_to_ndc = fit_ortho(s.mesh, setup.light.direction);
  return s;
}

Scene one_instance(const Mesh& mesh) {
  Scene s;
  s.meshes.push_back(mesh);
  s.instances.push_back(Instance{});
  return s;
}

}  // namespace shadow::bench
