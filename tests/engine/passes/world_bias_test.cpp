// The world-space caster bias of Kozlov 14.3.1 in transform_vertices (kernels/rasterizer.cl):
// clip = M (P + L (a + b texel(P))), against the same formula in double precision on the CPU,
// for a PSM matrix (directional light) and a spot light's perspective matrix (spot and point
// lights). texel(P) is the world size of one map texel at P across the light: the larger
// singular value of the inverse of d(map NDC)/d(world) restricted to the plane perpendicular to
// L, over the map size.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/engine.hpp"
#include "engine/light/psm_fit.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/plan/validate.hpp"
#include "occluder_scene.hpp"
#include "validation_error.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

double texel_size(const glm::dmat4& m, const glm::dvec3& p, const glm::dvec3& l, double size) {
  const glm::dvec3 t1 = glm::normalize(std::abs(l.x) < 0.9 ? glm::cross(l, glm::dvec3(1, 0, 0))
                                                           : glm::cross(l, glm::dvec3(0, 1, 0)));
  const glm::dvec3 t2 = glm::cross(l, t1);
  const glm::dvec4 c = m * glm::dvec4(p, 1.0);
  const glm::dvec2 ndc = glm::dvec2(c) / c.w;
  auto step = [&](const glm::dvec3& t) {
    const glm::dvec4 mt = m * glm::dvec4(t, 0.0);
    return (glm::dvec2(mt) - ndc * mt.w) / c.w;
  };
  const glm::dvec2 j1 = step(t1), j2 = step(t2);
  // The larger singular value of J^-1 is 1 / the smaller singular value of J.
  const double a = j1.x, b = j2.x, cc = j1.y, d = j2.y;
  const double s_min = 0.5 * std::abs(std::hypot(a + d, cc - b) - std::hypot(a - d, cc + b));
  return s_min > 0 ? 1.0 / (s_min * size) : 0.0;
}

struct Case {
  const char* name;
  Light light;
  glm::dmat4 m;
};

TEST(WorldBias, KernelMatchesTheDoubleFormula) {
  cl::Runtime runtime;
  cl::Kernels kernels(runtime);
  Rasterizer rasterizer(runtime, kernels);
  // A cloud of vertices in a 40 m box around (0, 2, -15), two instances (one moved).
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Mesh mesh;
  for (int i = 0; i < 3000; ++i) {
    mesh.positions.insert(mesh.positions.end(), {20 * u(rng), 2 + 5 * u(rng), -15 + 20 * u(rng)});
    mesh.indices.push_back(i);
  }
  auto scene = std::make_shared<Scene>();
  scene->meshes = {mesh};
  scene->instances = {Instance{0}, Instance{0}};
  scene->instances[1].transform = glm::translate(glm::mat4(1.0f), glm::vec3(3, 0.5f, -2));

  Camera cam;
  cam.eye = {0, 6, 10};
  cam.target = {0, 0, -20};
  cam.width = 320, cam.height = 180;
  cam.near = 0.5f, cam.far = 200.0f;
  std::vector<InstanceBounds> bounds = {{Bounds{{-20, -3, -35}, {23, 7.5f, 5}}, true, true}};
  Light sun;
  sun.direction = glm::normalize(glm::vec3(0.4f, -1.0f, -0.3f));
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {5, 30, -10};
  spot.direction = glm::normalize(glm::vec3(-0.1f, -1.0f, 0.0f));
  spot.cone_angle_deg = 100.0f;
  // A point light (kind LIGHT_POINT) pushes away from its position like a spot; any matrix will
  // do for the formula, here the spot's.
  Light point = spot;
  point.type = LightType::kPoint;
  const Case cases[] = {
      {"psm directional", sun, fit_psm_light(sun, cam, bounds, PsmSettings{}).setup.world_to_ndc},
      {"uniform spot", spot, fit_uniform_light(spot, cam, bounds).world_to_ndc},
      {"point", point, fit_uniform_light(spot, cam, bounds).world_to_ndc}};
  const uint32_t map = 1024;
  for (const Case& c : cases) {
    for (auto [a, b] : {std::pair{0.05f, 0.0f}, {0.0f, 1.0f}, {0.02f, 2.0f}}) {
      Timeline t;
      SceneBuffers buffers(runtime, kernels, *scene, t);
      auto draws =
          make_draws(*scene, buffers, glm::mat4(c.m), [](const Instance&) { return true; });
      WorldBias bias;
      bias.world_to_ndc = glm::mat4(c.m);
      bias.light = light_item(c.light);
      bias.constant = a, bias.texel = b, bias.map_size = map;
      const RasterOutput& out =
          rasterizer.run(buffers, draws, map, map, false, "test", "test", t, bias);
      const size_t n = mesh.positions.size() / 3 * 2;
      std::vector<glm::vec4> clip(n);
      runtime.read(out.clip, clip.data(), n * sizeof(glm::vec4));
      // The reference takes the float matrix and light the kernel got, in double.
      const glm::dmat4 m(bias.world_to_ndc);
      double worst = 0, worst_ndc = 0, texel_lo = INFINITY, texel_hi = 0;
      for (size_t o = 0; o < n; ++o) {
        const Instance& inst = scene->instances[o / (n / 2)];
        const size_t v = o % (n / 2);
        const glm::dvec3 p(glm::dmat4(inst.transform) * glm::dvec4(mesh.positions[3 * v],
                                                                   mesh.positions[3 * v + 1],
                                                                   mesh.positions[3 * v + 2], 1.0));
        const glm::dvec3 l = bias.light.kind == kLightDirectional
                                 ? glm::dvec3(bias.light.axis)
                                 : glm::normalize(p - glm::dvec3(bias.light.position));
        const double texel = texel_size(m, p, l, map);
        texel_lo = std::min(texel_lo, texel), texel_hi = std::max(texel_hi, texel);
        const glm::dvec4 want = m * glm::dvec4(p + l * (double(a) + double(b) * texel), 1.0);
        const glm::dvec4 got(clip[o]);
        // Relative to the size of the clip vector: what a float evaluation of M P can hold.
        worst = std::max(worst, glm::length(got - want) / glm::length(want));
        if (want.w > 0)
          worst_ndc =
              std::max(worst_ndc, glm::length(glm::dvec3(got) / got.w - glm::dvec3(want) / want.w));
      }
      std::printf(
          "[ bias     ] %s a %.2g b %.2g: texel %.3g..%.3g m, worst |clip err| / |clip| "
          "%.3g, worst NDC err %.3g\n",
          c.name, a, b, texel_lo, texel_hi, worst, worst_ndc);
      // Measured <= 1.43e-7 and 2.73e-7 (float M P + offset against double).
      EXPECT_LT(worst, 4e-7);
      EXPECT_LT(worst_ndc, 8e-7);
    }
  }
}

// The bias moves casters in the light's map only: the camera view (positions) is untouched,
// and a constant offset of 0.5 m straight away from a sun straight down deepens the map's
// depth of the occluder by exactly 0.5 m in its orthographic depth units.
TEST(WorldBias, OnlyTheLightsMapMoves) {
  RenderRequest r = testing::occluder_request();
  r.products = {Product::kShadowMap, Product::kPosition};
  Engine& e = testing::engine();
  const RenderResult plain = e.render(r);
  r.shadow_map.bias_world_constant = 0.5f;
  const RenderResult biased = e.render(r);
  ASSERT_EQ(plain.textures[1].data.size(), biased.textures[1].data.size());
  EXPECT_EQ(0, std::memcmp(plain.textures[1].data.data(), biased.textures[1].data.data(),
                           plain.textures[1].byte_size()));  // positions, bit for bit
  const glm::dmat4 m(plain.textures[0].world_to_ndc);
  const double dz_per_m = (m * glm::dvec4(0, -1, 0, 0)).z;  // NDC depth per metre down
  const std::vector<float>&a = plain.textures[0].data, &b = biased.textures[0].data;
  size_t moved = 0;
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i] >= 1.0f || b[i] >= 1.0f) continue;
    ++moved;
    worst = std::max(worst, std::abs((b[i] - a[i]) - 0.5 * dz_per_m));
  }
  std::printf(
      "[ bias     ] constant 0.5 m: %zu texels, worst depth error %.3g NDC (0.5 m = %.4g)\n", moved,
      worst, 0.5 * dz_per_m);
  EXPECT_GT(moved, 1000u);
  EXPECT_LT(worst, 1e-7);  // measured 1.5e-8
}

TEST(WorldBias, ValidationNamesTheField) {
  RenderRequest r = one_triangle_request();
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.shadow_map.bias_world_constant = -0.1f;
  EXPECT_NE(validation_error(r).find("shadow_map.bias_world_constant"), std::string::npos);
  r.shadow_map.bias_world_constant = 0.0f;
  r.shadow_map.bias_world_texel = NAN;
  EXPECT_NE(validation_error(r).find("shadow_map.bias_world_texel"), std::string::npos);
  r.shadow_map.bias_world_texel = 1.0f;
  r.shadow_map.psm.virtual_slide = INFINITY;
  EXPECT_NE(validation_error(r).find("shadow_map.psm_virtual_slide"), std::string::npos);
  r.shadow_map.psm.virtual_slide = 3.0;
  EXPECT_EQ(validation_error(r), "(accepted)");
}

}  // namespace
}  // namespace shadow
