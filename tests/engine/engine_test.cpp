// The engine end to end (no gRPC): closed-form shadows, the pass plan, determinism, and the
// field paths of validation errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>

#include "engine/cl/runtime.hpp"
#include "engine/device_types.hpp"
#include "engine/engine.hpp"
#include "occluder_scene.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

using testing::engine;
using testing::occluder_request;
using testing::quad;

const Texture& product(const RenderResult& r, const std::string& name) {
  for (const Texture& t : r.textures)
    if (t.name == name) return t;
  throw std::runtime_error("no product " + name);
}

// Shadow = the occluder's footprint |x|, |z| < 1 on the ground, exactly, away from its border.
TEST(Engine, SunStraightDownCastsTheSquaresFootprint) {
  RenderResult res = engine().render(occluder_request());
  const Texture& vis = product(res, "visibility");
  const Texture& pos = product(res, "position");
  size_t shadowed = 0, checked = 0;
  for (size_t p = 0; p < vis.data.size(); ++p) {
    float x = pos.data[3 * p], y = pos.data[3 * p + 1], z = pos.data[3 * p + 2];
    if (std::isnan(x)) {
      EXPECT_TRUE(std::isnan(vis.data[p]));
      continue;
    }
    if (y > 1.0f) continue;  // on the occluder itself: lit from above
    // 1024 texels over ~20 m: stay 2 texels away from the footprint's border.
    const float margin = 2 * 20.0f / 1024;
    float d = std::max(std::abs(x), std::abs(z));
    if (std::abs(d - 1.0f) < margin) continue;
    ++checked;
    float expected = d < 1.0f ? 0.0f : 1.0f;
    ASSERT_EQ(vis.data[p], expected) << "at " << x << "," << z;
    shadowed += expected == 0.0f;
  }
  EXPECT_GT(checked, 50000u);
  EXPECT_GT(shadowed, 200u);  // the occluder hides most of its footprint from this camera
}

// Position = the ray's hit on the plane y = 0, in closed form.
TEST(Engine, PositionIsTheCameraRaysHit) {
  RenderRequest r = occluder_request();
  r.products = {Product::kPosition};
  RenderResult res = engine().render(r);
  const Texture& pos = res.textures.at(0);
  glm::mat4 inv = glm::inverse(pos.world_to_ndc);
  double worst = 0;
  for (uint32_t j = 0; j < pos.height; ++j)
    for (uint32_t i = 0; i < pos.width; ++i) {
      size_t p = size_t{j} * pos.width + i;
      if (std::isnan(pos.data[3 * p]) || pos.data[3 * p + 1] > 1.0f) continue;
      glm::dvec2 uv((i + 0.5) / pos.width, (j + 0.5) / pos.height);
      glm::dvec4 a = glm::dmat4(inv) * glm::dvec4(uv, 0, 1),
                 b = glm::dmat4(inv) * glm::dvec4(uv, 1, 1);
      glm::dvec3 o = glm::dvec3(a) / a.w, d = glm::dvec3(b) / b.w - o;
      glm::dvec3 hit = o + d * (-o.y / d.y);
      worst = std::max(worst, glm::length(hit - glm::dvec3(pos.data[3 * p], pos.data[3 * p + 1],
                                                           pos.data[3 * p + 2])));
    }
  EXPECT_LT(worst, 1e-4);  // metres, for hits up to ~20 m away
}

TEST(Engine, RunsOnlyThePassesTheProductsNeed) {
  RenderRequest r = occluder_request();
  r.products = {Product::kShadowMap};
  RenderResult map_only = engine().render(r);
  for (const std::string& p : map_only.passes) EXPECT_EQ(p.find("gbuffer"), std::string::npos) << p;
  r.products = {Product::kPosition};
  RenderResult view_only = engine().render(r);
  for (const std::string& p : view_only.passes)
    EXPECT_EQ(p.find("shadow_map"), std::string::npos) << p;
  EXPECT_EQ(view_only.passes.size(), view_only.timings.size());
}

TEST(Engine, RepeatedRendersAreIdentical) {
  RenderRequest r = occluder_request();
  r.products = {Product::kShadowMap, Product::kVisibility};
  RenderResult a = engine().render(r), b = engine().render(r);
  for (size_t i = 0; i < a.textures.size(); ++i)
    EXPECT_EQ(0, std::memcmp(a.textures[i].data.data(), b.textures[i].data.data(),
                             a.textures[i].byte_size()));
}

TEST(Engine, SpotLightLeavesOutsideTheConeUnlit) {
  RenderRequest r = occluder_request();
  r.lights[0].type = LightType::kSpot;
  r.lights[0].position = {0, 6, 0};
  r.lights[0].direction = {0, -1, 0};
  r.lights[0].cone_angle_deg = 60.0f;  // radius on the ground: 6 tan 30 = 3.46 m
  RenderResult res = engine().render(r);
  const Texture& vis = product(res, "visibility");
  const Texture& pos = product(res, "position");
  for (size_t p = 0; p < vis.data.size(); ++p) {
    float x = pos.data[3 * p], y = pos.data[3 * p + 1], z = pos.data[3 * p + 2];
    if (std::isnan(x) || y > 1.0f) continue;
    float radius = std::hypot(x, z);
    if (radius > 3.5f) {
      EXPECT_EQ(vis.data[p], 0.0f);
    }
    // The occluder (half-size 1 at 4 m below the light) shadows |x|, |z| < 1.5 on the ground.
    if (radius < 3.4f && std::max(std::abs(x), std::abs(z)) > 1.55f) {
      EXPECT_EQ(vis.data[p], 1.0f);
    }
    if (std::max(std::abs(x), std::abs(z)) < 1.45f) {
      EXPECT_EQ(vis.data[p], 0.0f);
    }
  }
}

// The field Engine::check_scene names on `base` after `edit`, or "(accepted)".
std::string checked_field(const Scene& base, const std::function<void(Scene&)>& edit) {
  auto s = std::make_shared<Scene>(base);
  edit(*s);
  try {
    engine().check_scene(s);
  } catch (const InvalidArgument& e) {
    return e.field();
  }
  return "(accepted)";
}

// A scene kept for later requests (UploadScene) gets the device's per-vertex and per-index
// checks when it is kept, not only when a request first renders it (issue 40).
TEST(Engine, CheckSceneRunsTheDeviceChecks) {
  const std::shared_ptr<const Scene> scene = occluder_request().scene;
  const Scene& occluders = *scene;
  EXPECT_EQ(checked_field(occluders, [](Scene& s) { s.meshes[0].indices[4] = 4; }),
            "scene.meshes[0].indices[4]");
  EXPECT_EQ(checked_field(occluders, [](Scene& s) { s.meshes[1].positions[7] = NAN; }),
            "scene.meshes[1].positions[2]");
  EXPECT_EQ(checked_field(occluders, [](Scene&) {}), "(accepted)");
}

// On a mesh of several 4096-element chunks (scene_buffers.cl: a work-item or a work-group per
// chunk), the first bad index and the first non-finite vertex are the ones named, whichever chunk
// and work-item finds another one first.
TEST(Engine, CheckSceneNamesTheFirstBadElementOfALargeMesh) {
  auto base = std::make_shared<Scene>(*occluder_request().scene);
  Mesh& m = base->meshes[0];
  m.positions.clear(), m.indices.clear(), m.normals.clear(), m.uvs.clear();
  for (uint32_t v = 0; v < 9000; ++v)
    m.positions.insert(m.positions.end(), {float(v % 97), 0, float(v / 97)});
  for (uint32_t t = 0; t + 2 < 9000; t += 3) m.indices.insert(m.indices.end(), {t, t + 1, t + 2});
  EXPECT_EQ(checked_field(*base, [](Scene&) {}), "(accepted)");
  EXPECT_EQ(checked_field(*base,
                          [](Scene& s) {
                            s.meshes[0].indices[8191] = 9000;  // the last of chunk 1
                            s.meshes[0].indices[5000] = 9001;
                            s.meshes[0].indices[5001] = 9000;
                          }),
            "scene.meshes[0].indices[5000]");
  EXPECT_EQ(checked_field(*base,
                          [](Scene& s) {
                            s.meshes[0].positions[3 * 8500] = NAN;
                            s.meshes[0].positions[3 * 6000 + 1] = INFINITY;
                            s.meshes[0].positions[3 * 6255 + 2] = -INFINITY;
                          }),
            "scene.meshes[0].positions[6000]");
}

// Each bad field is named, and the engine keeps working afterwards.
TEST(Engine, ValidationNamesTheField) {
  auto expect_field = [](RenderRequest r, const std::string& field) {
    try {
      engine().render(r);
      ADD_FAILURE() << "no error for " << field;
    } catch (const InvalidArgument& e) {
      EXPECT_EQ(e.field(), field) << e.what();
    } catch (const ResourceExhausted& e) {
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  auto with_scene = [](std::function<void(Scene&)> edit) {
    RenderRequest r = occluder_request();
    auto s = std::make_shared<Scene>(*r.scene);
    edit(*s);
    r.scene = s;
    return r;
  };
  expect_field(with_scene([](Scene& s) { s.meshes[1].positions[7] = NAN; }),
               "scene.meshes[1].positions[2]");
  expect_field(with_scene([](Scene& s) { s.meshes[0].positions[0] = INFINITY; }),
               "scene.meshes[0].positions[0]");
  expect_field(with_scene([](Scene& s) { s.meshes[0].indices[4] = 4; }),
               "scene.meshes[0].indices[4]");
  expect_field(with_scene([](Scene& s) { s.meshes[1] = Mesh{}; }), "scene.meshes[1]");
  expect_field(with_scene([](Scene& s) { s.instances[1].mesh = 7; }), "scene.instances[1].mesh");
  RenderRequest r = occluder_request();
  r.lights[0].direction = {0, 0, 0};
  expect_field(r, "lights[0].directional.direction");
  r = occluder_request();
  r.camera.near = 0.0f;
  expect_field(r, "camera.near");
  r = occluder_request();
  r.camera.far = r.camera.near;
  expect_field(r, "camera.far");
  r = occluder_request();
  r.camera.fov_deg = 180.0f;
  expect_field(r, "camera.fov_deg");
  r = occluder_request();
  r.camera.width = 0;
  expect_field(r, "camera.width");
  r = occluder_request();
  r.camera.height = 1000000;
  expect_field(r, "camera.height");
  r = occluder_request();
  r.shadow_map.size = 100000;
  expect_field(r, "shadow_map.size");
  r = occluder_request();
  r.products.clear();
  expect_field(r, "products");
  r = occluder_request();
  r.lights[0].type = LightType::kPoint;
  r.shadow_map.technique = Technique::kUniform;
  expect_field(r, "lights[0].point");  // a point light with a single-map technique
  r.shadow_map.technique = Technique::kCube;
  r.filter.kind = FilterKind::kPcss;
  r.lights[0].size = 0.1f;
  expect_field(r, "filter.pcss");
  r.filter.kind = FilterKind::kBlur;
  expect_field(r, "filter.blur");
  r.filter.kind = FilterKind::kPoisson;
  r.shadow_map.size = 256;
  r.filter.poisson.radius = 31.5f;  // the guard band of a 256 face is at most 32 texels
  expect_field(r, "filter.poisson.radius");
  r.filter.kind = FilterKind::kHard;
  r.products = {Product::kVisibility, Product::kShadowMapMips};
  expect_field(r, "products[1]");
  r = occluder_request();
  r.shadow_map.technique = Technique::kCube;  // with a directional light
  expect_field(r, "shadow_map.technique");
  r = occluder_request();
  r.shadow_map.technique = Technique::kPsmCube;
  r.shadow_map.psm.near = PsmNear::kVirtualSlideBack;
  r.shadow_map.psm.virtual_slide = 1e17;  // near and far would merge in double
  expect_field(r, "shadow_map.psm_virtual_slide");
  EXPECT_NO_THROW(engine().render(occluder_request()));
}

// Stacked map-filling quads at 8192^2 overlap 16384 tiles per triangle: enough of them for 1.1x
// the device's own buffer limit in bin entries (3004 quads, 4.7 GB, on PoCL's 4 GiB; the limit
// of a 140 GB GPU needs ~25000). Refused by name before allocating; the engine keeps working.
// No cost limit, which would refuse that many first on a large device.
TEST(Engine, BinsOverTheBufferLimitAreResourceExhausted) {
  const uint64_t limit = cl::Device().max_alloc_bytes();
  const uint64_t per_quad = 2 * 16384 * kTriRecordBytes;
  const auto quads = static_cast<uint32_t>((limit + limit / 10) / per_quad + 1);
  EngineOptions options;
  options.max_request_cost_ms = 0;
  Engine uncapped(options);
  RenderRequest r = occluder_request();
  auto scene = std::make_shared<Scene>(*r.scene);
  Mesh stack;
  for (uint32_t k = 0; k < quads; ++k) {
    const float y = 1.0f + k * (0.3f / quads);
    const uint32_t b = 4 * k;
    stack.positions.insert(stack.positions.end(), {-10, y, -10, 10, y, -10, 10, y, 10, -10, y, 10});
    stack.indices.insert(stack.indices.end(), {b, b + 2, b + 1, b, b + 3, b + 2});
  }
  scene->meshes.push_back(stack);
  scene->instances.push_back(Instance{2});
  r.scene = scene;
  r.shadow_map.size = 8192;
  r.products = {Product::kShadowMap};
  try {
    uncapped.render(r);
    FAIL() << "no error";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "shadow_map.size") << e.what();
  }
  EXPECT_NO_THROW(uncapped.render(occluder_request()));
}

TEST(Engine, OutputOverTheByteLimitIsResourceExhausted) {
  Engine small(EngineOptions{.max_output_bytes = 1 << 20});
  RenderRequest r = occluder_request();
  r.products = {Product::kShadowMap};  // 1024^2 floats = 4 MiB
  try {
    small.render(r);
    FAIL() << "no error";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "products");
  }
}

}  // namespace
}  // namespace shadow
