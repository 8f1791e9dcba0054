#include "engine/light/virtual_levels.hpp"

#include <algorithm>
#include <bit>
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

VirtualLevels directional_clipmap(const Light& light, const glm::dvec3& eye, const Bounds& scene,
                                  uint32_t texels, int first_level, int last_level) {
  VirtualLevels c;
  c.texels = texels;
  const glm::dvec3 d = glm::normalize(glm::dvec3(light.direction));
  const glm::dvec3 a = glm::abs(d);
  // Anchored at the world's origin, so that windows and pages do not move with the camera.
  c.view = glm::lookAt(-d, glm::dvec3(0.0), a.y < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0));
  const Bounds ls = transform_bounds(scene, c.view);
  const double near = -ls.hi.z, far = -ls.lo.z;  // along the light's travel
  const double pad = 1e-3 * (far - near) + 1e-6 * std::max({1.0, std::abs(near), std::abs(far)});
  // Snapped outward to a power of two about an eighth of the extent, so that a caster moving
  // within the scene leaves the depth, and with it every page's texels, as they were.
  const double step = std::exp2(std::ceil(std::log2((far - near + 2 * pad) / 8)));
  c.depth = {MapDepth::kOrthographic, std::floor((near - pad) / step) * step,
             std::ceil((far + pad) / step) * step};
  const glm::dvec2 at(c.view * glm::dvec4(eye, 1.0));
  const double pages = double(texels / kPageTexels);
  for (int l = first_level; l <= last_level; ++l) {
    ClipmapLevel level;
    level.level = l;
    const double page = clipmap_texel(l, texels) * kPageTexels;
    // The camera's page lies in the window's middle quarter: the window moves in steps of a
    // quarter, so that a sequence's pages keep their window (and their texels) for a while.
    const double step = pages / 4;
    level.first_page = glm::floor((glm::floor(at / page) - pages / 2 + step / 2) / step) * step;
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

VirtualLevels fit_directional_clipmap(const Light& light, const Camera& camera, const Bounds& scene,
                                      uint32_t texels, double bias, uint32_t margin) {
  const glm::dvec3 eye(camera.eye);
  const VirtualLevels frame = directional_clipmap(light, eye, scene, texels, 0, -1);
  const glm::dvec2 at(frame.view * glm::dvec4(eye, 1.0));
  const Bounds ls = transform_bounds(scene, frame.view);
  // The farthest scene point from the eye across the light (Chebyshev: windows are squares).
  const double reach = std::max({std::abs(ls.lo.x - at.x), std::abs(ls.hi.x - at.x),
                                 std::abs(ls.lo.y - at.y), std::abs(ls.hi.y - at.y), 1e-6});
  // The window of level l reaches 3/8 of 2^l, less a page, from the eye's page on its near side
  // (the eye's page is in its middle quarter); less the margin:
  // 2^l (3/8 - (page + margin) / texels) >= reach.
  const double spare = 0.375 - double(kPageTexels + margin) / texels;
  const double pixel_angle =
      2 * std::tan(glm::radians(0.5 * double(camera.fov_deg))) / camera.height;
  // Past the level that holds the scene, the levels a pixel at the scene's farthest point reads
  // (its footprint, doubled for slanted receivers): they cost few pages, and a short pool's
  // coarsening climbs them.
  double farthest = 0;
  for (const glm::dvec3& corner : scene.corners())
    farthest = std::max(farthest, glm::length(corner - eye));
  const int last = std::max(int(std::ceil(std::log2(reach / spare))),
                            clipmap_level(2 * farthest * pixel_angle, bias, texels) + 1);
  const double pixel = double(camera.near) * pixel_angle;
  const int first = std::clamp(clipmap_level(pixel, bias, texels), last - kMaxLevels + 1, last);
  return directional_clipmap(light, eye, scene, texels, first, last);
}

int virtual_mips(LightType type, uint32_t texels) {
  const int to_a_page = std::countr_zero(texels / kPageTexels) + 1;
  return type == LightType::kPoint ? std::min(to_a_page, kMaxLevels / 6) : to_a_page;
}

VirtualLevels perspective_levels(const std::vector<ViewSetup>& faces, const CubeFaces& cube,
                                 uint32_t texels, int mips) {
  VirtualLevels c;
  c.faces = int(faces.size());
  c.mips = mips;
  c.cube = cube;
  c.texels = texels;
  for (const ViewSetup& face : faces) {
    c.face_ndc.push_back(face.world_to_ndc);
    for (int m = 0; m < mips; ++m) {
      ClipmapLevel level;
      level.level = m;
      level.first_page = glm::dvec2(0.0);
      level.setup = face;
      level.setup.faces = CubeFaces{};  // a map of its own: marking picks the faces (c.cube)
      c.levels.push_back(level);
    }
  }
  return c;
}

}  // namespace shadow
