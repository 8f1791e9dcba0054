// Proto <-> engine conversion of requests: round trips, the wire layout, defaults for absent
// fields, and the field paths of byte-level and presence errors.
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "wire/convert.hpp"
#include "wire/errors.hpp"

namespace shadow::convert {
namespace {

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

RenderRequest rich_request() {
  auto scene = std::make_shared<Scene>();
  Mesh tri;
  tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.indices = {0, 1, 2};
  tri.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  tri.uvs = {0, 0, 1, 0, 0, 1};
  Mesh quad;
  quad.positions = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
  quad.indices = {0, 3, 2, 0, 2, 1};
  scene->meshes = {tri, quad};
  glm::mat4 moved =
      glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3)), 0.7f, glm::vec3(0, 1, 0));
  scene->instances = {
      {1, glm::mat4(1.0f), true, true}, {0, moved, false, true}, {0, glm::mat4(2.0f), true, false}};

  RenderRequest r;
  r.scene = scene;
  r.camera = {{1, 2, 3}, {0, 0.5f, 0}, {0, 0, 1}, 45.0f, 640, 480, 0.5f, 50.0f};
  r.lights[0].type = LightType::kSpot;
  r.lights[0].position = {0, 10, 0};
  r.lights[0].direction = {0, -1, 0.1f};
  r.lights[0].cone_angle_deg = 70.0f;
  r.lights[0].size = 0.25f;
  r.shadow_map = {1024, Technique::kUniform, 0.002f, 1.5f};
  r.products = {Product::kPosition, Product::kShadowMap, Product::kVisibility};
  return r;
}

TEST(Convert, RequestRoundTripIsExact) {
  const RenderRequest in = rich_request();
  // Through serialized bytes, as on the wire.
  v1::RenderRequest wire;
  ASSERT_TRUE(wire.ParseFromString(to_proto(in).SerializeAsString()));
  const RenderRequest out = from_proto(wire);

  ASSERT_EQ(out.scene->meshes.size(), in.scene->meshes.size());
  for (size_t i = 0; i < in.scene->meshes.size(); ++i) {
    const Mesh& a = in.scene->meshes[i];
    const Mesh& b = out.scene->meshes[i];
    EXPECT_TRUE(same_bits(a.positions, b.positions)) << i;
    EXPECT_EQ(a.indices, b.indices) << i;
    EXPECT_TRUE(same_bits(a.normals, b.normals)) << i;
    EXPECT_TRUE(same_bits(a.uvs, b.uvs)) << i;
  }
  ASSERT_EQ(out.scene->instances.size(), in.scene->instances.size());
  for (size_t j = 0; j < in.scene->instances.size(); ++j) {
    const Instance& a = in.scene->instances[j];
    const Instance& b = out.scene->instances[j];
    EXPECT_EQ(a.mesh, b.mesh);
    EXPECT_EQ(a.transform, b.transform);
    EXPECT_EQ(a.casts_shadows, b.casts_shadows);
    EXPECT_EQ(a.receives_shadows, b.receives_shadows);
  }
  EXPECT_EQ(out.camera.eye, in.camera.eye);
  EXPECT_EQ(out.camera.target, in.camera.target);
  EXPECT_EQ(out.camera.up, in.camera.up);
  EXPECT_EQ(out.camera.fov_deg, in.camera.fov_deg);
  EXPECT_EQ(out.camera.width, in.camera.width);
  EXPECT_EQ(out.camera.height, in.camera.height);
  EXPECT_EQ(out.camera.near, in.camera.near);
  EXPECT_EQ(out.camera.far, in.camera.far);
  EXPECT_EQ(out.lights[0].type, LightType::kSpot);
  EXPECT_EQ(out.lights[0].position, in.lights[0].position);
  EXPECT_EQ(out.lights[0].direction, in.lights[0].direction);
  EXPECT_EQ(out.lights[0].cone_angle_deg, in.lights[0].cone_angle_deg);
  EXPECT_EQ(out.lights[0].size, in.lights[0].size);
  EXPECT_EQ(out.shadow_map.size, in.shadow_map.size);
  EXPECT_EQ(out.shadow_map.bias_constant, in.shadow_map.bias_constant);
  EXPECT_EQ(out.shadow_map.bias_slope, in.shadow_map.bias_slope);
  EXPECT_EQ(out.products, in.products);
}

TEST(Convert, EveryLightKindRoundTrips) {
  Light directional;
  directional.type = LightType::kDirectional;
  directional.direction = {0.3f, -1, 0.2f};
  directional.size = 0.53f;
  Light point;
  point.type = LightType::kPoint;
  point.position = {4, 5, 6};
  point.size = 0.1f;
  for (const Light& in : {directional, point}) {
    const Light out = from_proto(to_proto(in));
    EXPECT_EQ(out.type, in.type);
    EXPECT_EQ(out.size, in.size);
    if (in.type == LightType::kDirectional) {
      EXPECT_EQ(out.direction, in.direction);
    } else {
      EXPECT_EQ(out.position, in.position);
    }
  }
  EXPECT_TRUE(to_proto(directional).has_directional());
  EXPECT_TRUE(to_proto(point).has_point());
}

TEST(Convert, WireLayoutIsLittleEndianAndColumnMajor) {
  Mesh mesh;
  mesh.positions = {1.0f, -2.0f, 0.0f};
  mesh.indices = {1, 0x01020304, 0};
  const v1::Mesh m = to_proto(mesh);
  ASSERT_EQ(m.positions().size(), 12u);
  EXPECT_EQ(m.positions().substr(0, 8), std::string("\x00\x00\x80\x3f\x00\x00\x00\xc0", 8));
  ASSERT_EQ(m.indices().size(), 12u);
  EXPECT_EQ(m.indices().substr(0, 8), std::string("\x01\x00\x00\x00\x04\x03\x02\x01", 8));
  EXPECT_TRUE(m.normals().empty());

  const v1::Mat4 t = to_proto(glm::translate(glm::mat4(1.0f), glm::vec3(7, 8, 9)));
  ASSERT_EQ(t.m_size(), 16);
  EXPECT_EQ(t.m(12), 7.0f);
  EXPECT_EQ(t.m(13), 8.0f);
  EXPECT_EQ(t.m(14), 9.0f);
  EXPECT_EQ(t.m(3), 0.0f);
}

TEST(Convert, AbsentOptionalFieldsTakeTheirDefaults) {
  v1::RenderRequest r;
  v1::Camera* camera = r.mutable_camera();
  camera->mutable_eye()->set_z(5);
  camera->mutable_target();  // present, all zero: the origin
  camera->set_width(8);
  camera->set_height(4);
  r.add_lights()->mutable_directional()->mutable_direction()->set_y(-1);
  r.add_products(v1::PRODUCT_SHADOW_MAP);
  v1::Mesh* mesh = r.mutable_scene()->add_meshes();
  *mesh = to_proto(rich_request().scene->meshes[0]);
  r.mutable_scene()->add_instances();  // mesh 0, no transform, no flags

  const RenderRequest out = from_proto(r);
  EXPECT_EQ(out.camera.up, glm::vec3(0, 1, 0));
  EXPECT_EQ(out.camera.fov_deg, 60.0f);
  EXPECT_EQ(out.camera.near, 0.1f);
  EXPECT_EQ(out.camera.far, 1000.0f);
  EXPECT_EQ(out.camera.target, glm::vec3(0));
  EXPECT_EQ(out.shadow_map.size, 2048u);
  EXPECT_EQ(out.shadow_map.technique, Technique::kDefault);  // resolved per light
  ASSERT_EQ(out.scene->instances.size(), 1u);
  EXPECT_EQ(out.scene->instances[0].transform, glm::mat4(1.0f));
  EXPECT_TRUE(out.scene->instances[0].casts_shadows);
  EXPECT_TRUE(out.scene->instances[0].receives_shadows);

  // A present zero is a value, not "absent": the engine gets it and judges it.
  r.mutable_shadow_map()->set_size(0);
  r.mutable_camera()->set_near(0);
  const RenderRequest zeros = from_proto(r);
  EXPECT_EQ(zeros.shadow_map.size, 0u);
  EXPECT_EQ(zeros.camera.near, 0.0f);
}

struct BadWire {
  const char* name;
  std::function<void(v1::RenderRequest&)> mutate;
  const char* field;
};

class ConvertErrors : public ::testing::TestWithParam<BadWire> {};

TEST_P(ConvertErrors, NameTheField) {
  v1::RenderRequest r = to_proto(rich_request());
  GetParam().mutate(r);
  try {
    from_proto(r);
    FAIL() << "no error for " << GetParam().name;
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.field(), GetParam().field) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(std::string(GetParam().field) + ": ", 0), 0u) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Wire, ConvertErrors,
    ::testing::Values(
        BadWire{
            "positions_13_bytes",
            [](auto& r) { r.mutable_scene()->mutable_meshes(1)->mutable_positions()->append("x"); },
            "scene.meshes[1].positions"},
        BadWire{"positions_one_float_short",
                [](auto& r) {
                  auto* p = r.mutable_scene()->mutable_meshes(0)->mutable_positions();
                  p->resize(p->size() - 4);
                },
                "scene.meshes[0].positions"},
        BadWire{"indices_8_bytes",
                [](auto& r) {
                  r.mutable_scene()->mutable_meshes(1)->set_indices(std::string(8, '\0'));
                },
                "scene.meshes[1].indices"},
        BadWire{"normals_short",
                [](auto& r) {
                  r.mutable_scene()->mutable_meshes(0)->set_normals(std::string(24, '\0'));
                },
                "scene.meshes[0].normals"},
        BadWire{
            "uvs_not_pairs",
            [](auto& r) { r.mutable_scene()->mutable_meshes(0)->set_uvs(std::string(12, '\0')); },
            "scene.meshes[0].uvs"},
        BadWire{"transform_15_values",
                [](auto& r) {
                  r.mutable_scene()
                      ->mutable_instances(2)
                      ->mutable_transform()
                      ->mutable_m()
                      ->RemoveLast();
                },
                "scene.instances[2].transform.m"},
        BadWire{"no_camera", [](auto& r) { r.clear_camera(); }, "camera"},
        BadWire{"no_eye", [](auto& r) { r.mutable_camera()->clear_eye(); }, "camera.eye"},
        BadWire{"no_target", [](auto& r) { r.mutable_camera()->clear_target(); }, "camera.target"},
        BadWire{"light_without_kind", [](auto& r) { r.mutable_lights(0)->clear_kind(); },
                "lights[0]"},
        BadWire{"directional_without_direction",
                [](auto& r) { r.mutable_lights(0)->mutable_directional(); },
                "lights[0].directional.direction"},
        BadWire{"spot_without_position",
                [](auto& r) { r.mutable_lights(0)->mutable_spot()->clear_position(); },
                "lights[0].spot.position"},
        BadWire{"point_without_position", [](auto& r) { r.mutable_lights(0)->mutable_point(); },
                "lights[0].point.position"},
        BadWire{"no_products", [](auto& r) { r.clear_products(); }, "products"},
        BadWire{"unspecified_product", [](auto& r) { r.set_products(1, v1::PRODUCT_UNSPECIFIED); },
                "products[1]"},
        BadWire{"unknown_product", [](auto& r) { r.set_products(0, v1::Product(99)); },
                "products[0]"},
        BadWire{"unknown_technique",
                [](auto& r) { r.mutable_shadow_map()->set_technique(v1::Technique(42)); },
                "shadow_map.technique"}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace shadow::convert

namespace shadow::convert {
namespace {

// The atlas' density: present = the client's value, absent = 0 (the map's footprint); a tile
// and a density each travel only where set.
TEST(Convert, AtlasDensityTravelsAndAbsentMeansTheMapsFootprint) {
  v1::RenderRequest r = to_proto(rich_request());
  r.add_products(v1::PRODUCT_SHADOW_ATLAS);
  EXPECT_FALSE(r.atlas().has_tile_size());
  EXPECT_FALSE(r.atlas().has_texel_world_size());
  RenderRequest out = from_proto(r);
  EXPECT_EQ(out.atlas.tile, 0u);  // sized per instance
  EXPECT_EQ(out.atlas.texel_world_size, 0.0);

  r.mutable_atlas()->set_texel_world_size(0.125);
  out = from_proto(r);
  EXPECT_EQ(out.atlas.texel_world_size, 0.125);
  const v1::RenderRequest back = to_proto(out);
  EXPECT_TRUE(back.atlas().has_texel_world_size());
  EXPECT_EQ(back.atlas().texel_world_size(), 0.125);
  EXPECT_FALSE(back.atlas().has_tile_size());

  r.mutable_atlas()->clear_texel_world_size();
  r.mutable_atlas()->set_tile_size(128);
  out = from_proto(r);
  EXPECT_EQ(out.atlas.tile, 128u);
  EXPECT_EQ(to_proto(out).atlas().tile_size(), 128u);
  EXPECT_FALSE(to_proto(out).atlas().has_texel_world_size());
}

// An unset fit is the one the request needs: MAP_FIT_SCENE with an atlas product or filter,
// VIEW otherwise; a fit the client named is never replaced.
TEST(Convert, AnUnsetFitIsTheSceneForTheAtlasAndANamedFitStays) {
  v1::RenderRequest r = to_proto(rich_request());
  r.mutable_shadow_map()->clear_fit();
  EXPECT_EQ(from_proto(r).shadow_map.fit, MapFit::kView);  // no atlas

  for (const v1::Product atlas :
       {v1::PRODUCT_SHADOW_ATLAS, v1::PRODUCT_SHADOW_ATLAS_MIPS, v1::PRODUCT_SHADOW_ATLAS_SAT}) {
    v1::RenderRequest a = r;
    a.add_products(atlas);
    EXPECT_EQ(from_proto(a).shadow_map.fit, MapFit::kScene) << v1::Product_Name(atlas);
    a.mutable_shadow_map()->set_fit(v1::MAP_FIT_VIEW);  // named: the engine refuses it
    EXPECT_EQ(from_proto(a).shadow_map.fit, MapFit::kView) << v1::Product_Name(atlas);
  }
  for (const bool sat : {true, false}) {
    v1::RenderRequest f = r;
    if (sat)
      f.mutable_filter()->mutable_atlas_sat();
    else
      f.mutable_filter()->mutable_atlas_mip();
    EXPECT_EQ(from_proto(f).shadow_map.fit, MapFit::kScene) << sat;
    f.mutable_shadow_map()->set_fit(v1::MAP_FIT_VIEW);
    EXPECT_EQ(from_proto(f).shadow_map.fit, MapFit::kView) << sat;
    f.mutable_shadow_map()->set_fit(v1::MAP_FIT_SCENE);
    EXPECT_EQ(from_proto(f).shadow_map.fit, MapFit::kScene) << sat;
  }
}

}  // namespace
}  // namespace shadow::convert
