#include "engine/light/virtual_levels.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace shadow {

double clipmap_texel(int level, uint32_t texels) {
  return std::ldexp(1.0, level) / double(texels);
}

int clipmap_level(double footprint, double bias, uint32_t texels) {
  // 2^l / texels <= footprint * 2^bias  <=>  l <= log2(footprint * texels) + bias.
  return int(std::floor(std::log2(footprint * double(texels)) + bias));
}

DirectionalClipmap directional_clipmap(const Light& light, const glm::dvec3& eye,
                                       const Bounds& scene, uint32_t texels, int first_level,
                                       int last_level) {
  DirectionalClipmap c;
  c.texels = texels;
  const glm::dvec3 d = glm::normalize(glm::dvec3(light.direction));
  const glm::dvec3 a = glm::abs(d);
  // Anchored at the world's origin, so that windows and pages do not move with the camera.
  c.view = glm::lookAt(-d, glm::dvec3(0.0), a.y < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0));
  const Bounds ls = transform_bounds(scene, c.view);
  const double near = -ls.hi.z, far = -ls.lo.z;  // along the light's travel
  const double pad = 1e-3 * (far - near) + 1e-6 * std::max({1.0, std::abs(near), std::abs(far)});
  c.depth = {MapDepth::kOrthographic, near - pad, far + pad};
  const glm::dvec2 at(c.view * glm::dvec4(eye, 1.0));
  const double pages = double(texels / kPageTexels);
  for (int l = first_level; l <= last_level; ++l) {
    ClipmapLevel level;
    level.level = l;
    const double page = clipmap_texel(l, texels) * kPageTexels;
    level.first_page = glm::floor(at / page) - pages / 2;
    const glm::dvec2 lo = level.first_page * page, hi = lo + pages * page;
    level.setup.view = c.view;
    // Bottom and top swapped: texture rows then grow with light-space v, as page rows do.
    level.setup.world_to_ndc = gl_to_texture_ndc() *
                               glm::ortho(lo.x, hi.x, hi.y, lo.y, c.depth.near, c.depth.far) *
                               c.view;
    level.setup.depth = c.depth;
    c.levels.push_back(level);
  }
  return c;
}

}  // namespace shadow
