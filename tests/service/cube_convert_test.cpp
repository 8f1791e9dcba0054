// Cube maps on the wire: TECHNIQUE_CUBE and TECHNIQUE_PSM_CUBE both ways, the light-dependent
// default of TECHNIQUE_UNSPECIFIED (an explicit technique is never replaced), cube textures with
// per-face matrices through the stream (including one with no face rendered), the per-face fit
// report, and the malformed cube headers the assembler refuses.
#include <algorithm>
#include <cstring>
#include <functional>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "stream_helpers.hpp"
#include "wire/convert.hpp"
#include "wire/errors.hpp"
#include "wire/result_assembler.hpp"
#include "wire/result_slicer.hpp"

namespace shadow::convert {
namespace {

// A small request whose light and technique the tests set.
v1::RenderRequest request_with(const v1::Light& light, v1::Technique technique) {
  v1::RenderRequest r;
  v1::Camera* camera = r.mutable_camera();
  camera->mutable_eye()->set_z(5);
  camera->mutable_target();
  camera->set_width(8);
  camera->set_height(4);
  *r.add_lights() = light;
  r.mutable_shadow_map()->set_technique(technique);
  r.add_products(v1::PRODUCT_SHADOW_MAP);
  Mesh tri;
  tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.indices = {0, 1, 2};
  *r.mutable_scene()->add_meshes() = to_proto(tri);
  r.mutable_scene()->add_instances();
  return r;
}

v1::Light light_of(LightType type) {
  Light light;
  light.type = type;
  light.position = {0, 3, 0};
  return to_proto(light);
}

TEST(CubeConvert, TechniqueRoundTrips) {
  ShadowMapSettings s;
  s.technique = Technique::kCube;
  v1::ShadowMapSettings wire;
  ASSERT_TRUE(wire.ParseFromString(to_proto(s).SerializeAsString()));
  EXPECT_EQ(wire.technique(), v1::TECHNIQUE_CUBE);
  // The wire value is kept whatever the light; the engine judges the pair.
  EXPECT_EQ(from_proto(wire).technique, Technique::kCube);
}

// The engine resolves kDefault per light (engine/plan/light_request.hpp, light_request_test).
TEST(CubeConvert, UnspecifiedIsTheDefaultWhateverTheLight) {
  const auto technique = [](LightType light, v1::Technique t) {
    return from_proto(request_with(light_of(light), t)).shadow_map.technique;
  };
  EXPECT_EQ(technique(LightType::kPoint, v1::TECHNIQUE_UNSPECIFIED), Technique::kDefault);
  EXPECT_EQ(technique(LightType::kDirectional, v1::TECHNIQUE_UNSPECIFIED), Technique::kDefault);
  EXPECT_EQ(technique(LightType::kSpot, v1::TECHNIQUE_UNSPECIFIED), Technique::kDefault);
  // Nothing the client sent is changed: the engine rejects these pairs with its own error.
  EXPECT_EQ(technique(LightType::kPoint, v1::TECHNIQUE_UNIFORM), Technique::kUniform);
  EXPECT_EQ(technique(LightType::kPoint, v1::TECHNIQUE_PSM), Technique::kPsm);
  EXPECT_EQ(technique(LightType::kDirectional, v1::TECHNIQUE_CUBE), Technique::kCube);
  EXPECT_EQ(technique(LightType::kPoint, v1::TECHNIQUE_PSM_CUBE), Technique::kPsmCube);
  EXPECT_EQ(technique(LightType::kDirectional, v1::TECHNIQUE_PSM_CUBE), Technique::kPsmCube);
  EXPECT_EQ(technique(LightType::kSpot, v1::TECHNIQUE_PSM_CUBE), Technique::kPsmCube);

  // Absent shadow-map settings are the same as an unspecified technique.
  v1::RenderRequest r = request_with(light_of(LightType::kPoint), v1::TECHNIQUE_UNSPECIFIED);
  r.clear_shadow_map();
  EXPECT_EQ(from_proto(r).shadow_map.technique, Technique::kDefault);
}

TEST(CubeConvert, UnknownTechniqueIsNamed) {
  v1::RenderRequest r = request_with(light_of(LightType::kPoint),
                                     static_cast<v1::Technique>(99));  // no such technique
  try {
    from_proto(r);
    FAIL() << "accepted technique 99";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.field(), "shadow_map.technique") << e.what();
    EXPECT_NE(std::string(e.what()).find("unknown technique 99"), std::string::npos) << e.what();
  }
}

Texture cube_texture(const std::vector<std::string>& names) {
  Texture t;
  t.name = "shadowmap_cube";
  t.kind = Product::kShadowMap;
  t.width = 5;
  t.height = 3;
  t.faces = uint32_t(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    const float k = float(i + 1);
    t.cube_faces.push_back({names[i], glm::perspective(1.5f + 0.01f * k, 1.0f, 0.1f * k, 10.0f),
                            glm::lookAt(glm::vec3(k, 2, 3), glm::vec3(0), glm::vec3(0, 1, 0))});
  }
  t.data.resize(size_t(t.width) * t.height * t.faces);
  for (size_t i = 0; i < t.data.size(); ++i) t.data[i] = float(i) * 0.125f;
  return t;
}

RenderResult cube_result(const std::vector<std::string>& names) {
  RenderResult r;
  r.light_fits.resize(1);
  r.textures.push_back(cube_texture(names));
  r.light_fits[0].light_case = "cube: point light";
  for (const char* face : {"+x", "-x", "+y", "-y", "+z", "-z"}) {
    const bool rendered = std::find(names.begin(), names.end(), face) != names.end();
    r.light_fits[0].cube_faces.push_back(
        {face, rendered, rendered ? "casters in front of visible receivers" : "no receiver"});
  }
  return r;
}

TEST(CubeConvert, CubeTextureAndFaceReportRoundTrip) {
  const RenderResult in = cube_result({"+x", "-y", "+z"});
  const auto messages = stream(in, 24);
  const v1::TextureInfo& info = messages[0].header().textures(0);
  EXPECT_EQ(info.faces(), 3u);
  EXPECT_EQ(info.cube_faces_size(), 3);
  EXPECT_EQ(info.byte_size(), 5u * 3 * 3 * 4);
  EXPECT_EQ(messages[0].header().light_fits(0).cube_faces_size(), 6);

  const RenderResult out = assemble(messages);
  ASSERT_EQ(out.textures.size(), 1u);
  const Texture& a = in.textures[0];
  const Texture& b = out.textures[0];
  EXPECT_EQ(b.name, "shadowmap_cube");
  EXPECT_EQ(b.faces, 3u);
  ASSERT_EQ(b.cube_faces.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(b.cube_faces[i].name, a.cube_faces[i].name);
    EXPECT_EQ(b.cube_faces[i].world_to_ndc, a.cube_faces[i].world_to_ndc) << i;
    EXPECT_EQ(b.cube_faces[i].world_to_camera, a.cube_faces[i].world_to_camera) << i;
  }
  EXPECT_NE(b.cube_faces[0].world_to_ndc, b.cube_faces[1].world_to_ndc);
  ASSERT_EQ(b.data.size(), a.data.size());
  EXPECT_EQ(std::memcmp(a.data.data(), b.data.data(), a.byte_size()), 0);

  ASSERT_EQ(out.light_fits[0].cube_faces.size(), 6u);
  for (size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(out.light_fits[0].cube_faces[i].name, in.light_fits[0].cube_faces[i].name);
    EXPECT_EQ(out.light_fits[0].cube_faces[i].rendered, in.light_fits[0].cube_faces[i].rendered);
    EXPECT_EQ(out.light_fits[0].cube_faces[i].reason, in.light_fits[0].cube_faces[i].reason);
  }
  EXPECT_TRUE(out.light_fits[0].cube_faces[4].rendered);
  EXPECT_FALSE(out.light_fits[0].cube_faces[5].rendered);
}

TEST(CubeConvert, PlainTexturesCarryNoFacesOrFaceReport) {
  RenderResult r;
  r.textures.push_back(cube_texture({}));
  r.textures[0].faces = 1;
  r.textures[0].data.resize(5 * 3);
  const auto messages = stream(r, 64);
  EXPECT_EQ(messages[0].header().textures(0).cube_faces_size(), 0);
  EXPECT_EQ(messages[0].header().light_fits_size(), 0);
  const RenderResult out = assemble(messages);
  EXPECT_EQ(out.textures[0].faces, 1u);
  EXPECT_TRUE(out.textures[0].cube_faces.empty());
  EXPECT_TRUE(out.light_fits.empty());
}

TEST(CubeConvert, CubeWithNoRenderedFaceIsAnEmptyTexture) {
  const RenderResult in = cube_result({});
  const auto messages = stream(in, 64);
  ASSERT_EQ(messages.size(), 1u);  // the header only: no bytes to send
  EXPECT_EQ(messages[0].header().textures(0).faces(), 0u);
  EXPECT_EQ(messages[0].header().textures(0).byte_size(), 0u);
  const RenderResult out = assemble(messages);
  ASSERT_EQ(out.textures.size(), 1u);
  EXPECT_EQ(out.textures[0].faces, 0u);
  EXPECT_TRUE(out.textures[0].cube_faces.empty());
  EXPECT_TRUE(out.textures[0].data.empty());
  ASSERT_EQ(out.light_fits[0].cube_faces.size(), 6u);
  EXPECT_FALSE(out.light_fits[0].cube_faces[0].rendered);
}

TEST(CubeConvert, ServerRefusesFacesThatDoNotMatchTheData) {
  RenderResult r = cube_result({"+x", "-x"});
  r.textures[0].cube_faces.pop_back();  // 2 faces of data, 1 described
  EXPECT_THROW(stream_result(r, 64, [](const v1::RenderResponse&) { return true; }),
               std::logic_error);
}

// Each case breaks the header of a good 3-face cube stream; the assembler must name the field.
struct BadCube {
  const char* name;
  std::function<void(v1::TextureInfo&)> apply;
  const char* message;
};

class MalformedCube : public ::testing::TestWithParam<BadCube> {};

TEST_P(MalformedCube, IsRejectedNamingTheField) {
  auto messages = stream(cube_result({"+x", "-y", "+z"}), 1 << 20);
  GetParam().apply(*messages[0].mutable_header()->mutable_textures(0));
  try {
    assemble(messages);
    FAIL() << "accepted " << GetParam().name;
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find(GetParam().message), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Header, MalformedCube,
    ::testing::Values(
        BadCube{"one_face_missing", [](auto& t) { t.mutable_cube_faces()->RemoveLast(); },
                "textures[0].cube_faces holds 2 entries for 3 faces"},
        BadCube{"faces_without_descriptions", [](auto& t) { t.mutable_cube_faces()->Clear(); },
                "textures[0].cube_faces holds 0 entries for 3 faces"},
        BadCube{"extra_face",
                [](auto& t) {
                  *t.add_cube_faces() = t.cube_faces(0);
                  t.mutable_cube_faces(3)->set_name("-z");
                },
                "textures[0].cube_faces holds 4 entries for 3 faces"},
        BadCube{"unknown_face_name", [](auto& t) { t.mutable_cube_faces(1)->set_name("up"); },
                "textures[0].cube_faces[1].name 'up' is not"},
        BadCube{"face_twice", [](auto& t) { t.mutable_cube_faces(2)->set_name("+x"); },
                "textures[0].cube_faces[2].name '+x' appears twice"},
        BadCube{"face_matrix_15_values",
                [](auto& t) {
                  t.mutable_cube_faces(1)->mutable_world_to_ndc()->mutable_m()->RemoveLast();
                },
                "textures[0].cube_faces[1].world_to_ndc.m"},
        BadCube{"face_without_camera",
                [](auto& t) { t.mutable_cube_faces(0)->clear_world_to_camera(); },
                "textures[0].cube_faces[0].world_to_camera.m"},
        // Seven faces of data would need a seventh name; the byte size fits the shape.
        BadCube{"seven_faces",
                [](auto& t) {
                  t.set_faces(7);
                  t.set_byte_size(5 * 3 * 7 * 4);
                },
                "textures[0].cube_faces holds 3 entries for 7 faces"}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace shadow::convert
