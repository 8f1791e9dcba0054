// shadowctl's request building: JSON, the demo's suggestions and flags, in that precedence.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "flag_error.hpp"
#include "scenes/demo_scene.hpp"
#include "shadowctl/args.hpp"
#include "shadowctl/request.hpp"
#include "temp_dir.hpp"

namespace shadow::ctl {
namespace {

using shadow::testing::TempDir;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr const char* kTriangleObj = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n";

// Camera, light, shadow map and products in canonical JSON (lowerCamelCase, enum names).
constexpr const char* kJson = R"({
  "camera": {"eye": {"x": 1, "y": 2, "z": 3}, "target": {}, "fovDeg": 45,
             "width": 640, "height": 480, "near": 0.5},
  "lights": [{"spot": {"position": {"y": 10}, "direction": {"y": -1}, "coneAngleDeg": 30},
            "size": 0.25}],
  "shadowMap": {"size": 1024, "biasConstant": 0.001},
  "products": ["PRODUCT_VISIBILITY"]
})";

TEST(BuildRequest, JsonFieldsSurviveAndFlagsOverrideThem) {
  TempDir dir;
  RequestFlags f;
  f.request = dir.write("req.json", kJson).string();
  f.scene = dir.write("tri.obj", kTriangleObj).string();
  f.fov = "30";
  f.lights = {"directional:0,-1,1"};
  f.bias_slope = "2";
  const v1::RenderRequest r = build_request(f);

  EXPECT_EQ(r.scene().meshes_size(), 1);
  EXPECT_EQ(r.scene().meshes(0).indices().size(), 12u);
  EXPECT_EQ(r.camera().eye().z(), 3.0f);       // from JSON
  EXPECT_EQ(r.camera().width(), 640u);         // from JSON
  EXPECT_EQ(r.camera().near(), 0.5f);          // from JSON
  EXPECT_FALSE(r.camera().has_far());          // nobody gave it: the server's default
  EXPECT_EQ(r.camera().fov_deg(), 30.0f);      // flag beats JSON
  ASSERT_TRUE(r.lights(0).has_directional());  // --light replaces the kind...
  EXPECT_EQ(r.lights(0).directional().direction().z(), 1.0f);
  EXPECT_EQ(r.lights(0).size(), 0.25f);  // ...but keeps the JSON's size
  EXPECT_EQ(r.shadow_map().size(), 1024u);
  EXPECT_EQ(r.shadow_map().bias_constant(), 0.001f);
  EXPECT_EQ(r.shadow_map().bias_slope(), 2.0f);
  ASSERT_EQ(r.products_size(), 1);  // JSON's list, not the default
  EXPECT_EQ(r.products(0), v1::PRODUCT_VISIBILITY);
}

TEST(BuildRequest, FlagsAloneWithDefaults) {
  TempDir dir;
  RequestFlags f;
  f.scene = dir.write("tri.obj", kTriangleObj).string();
  f.eye = "0,5,5";
  f.target = "0,0,0";
  f.lights = {"point:1,2,3"};
  f.light_size = "0.1";  // read by the soft filters only
  f.filter = "pcss";
  f.map_size = "512";
  f.technique = "uniform";
  const v1::RenderRequest r = build_request(f);
  EXPECT_EQ(r.camera().width(), kDefaultWidth);
  EXPECT_EQ(r.camera().height(), kDefaultHeight);
  EXPECT_FALSE(r.camera().has_up());
  ASSERT_TRUE(r.lights(0).has_point());
  EXPECT_EQ(r.lights(0).size(), 0.1f);
  EXPECT_EQ(r.shadow_map().size(), 512u);
  EXPECT_EQ(r.shadow_map().technique(), v1::TECHNIQUE_UNIFORM);
  ASSERT_EQ(r.products_size(), 3);
  EXPECT_EQ(r.products(0), v1::PRODUCT_SHADOW_MAP);
  EXPECT_EQ(r.products(2), v1::PRODUCT_POSITION);

  f.products = "position,shadowmap";
  const v1::RenderRequest p = build_request(f);
  ASSERT_EQ(p.products_size(), 2);
  EXPECT_EQ(p.products(0), v1::PRODUCT_POSITION);
}

TEST(BuildRequest, DemoSuggestsCameraAndLightOnlyWhereNoneIsGiven) {
  const scenes::DemoSetup demo = scenes::demo_scene();
  RequestFlags f;
  f.scene = kDemoScene;
  f.eye = "1,1,1";
  const v1::RenderRequest r = build_request(f);
  EXPECT_EQ(r.scene().meshes_size(), static_cast<int>(demo.scene.meshes.size()));
  EXPECT_EQ(r.scene().instances_size(), static_cast<int>(demo.scene.instances.size()));
  EXPECT_EQ(r.camera().eye().x(), 1.0f);  // the flag
  EXPECT_EQ(r.camera().target().y(), demo.camera.target.y);
  EXPECT_EQ(r.camera().fov_deg(), demo.camera.fov_deg);
  ASSERT_TRUE(r.lights(0).has_directional());
  EXPECT_EQ(r.lights(0).directional().direction().x(), demo.light.direction.x);
  EXPECT_EQ(r.shadow_map().bias_slope(), demo.shadow_map.bias_slope);
  EXPECT_GT(r.shadow_map().bias_slope(), 0.0f);

  TempDir dir;
  f.request = dir.write("req.json", kJson).string();
  const v1::RenderRequest j = build_request(f);
  EXPECT_EQ(j.camera().fov_deg(), 45.0f);  // the JSON's camera, not the demo's
  EXPECT_TRUE(j.lights(0).has_spot());
  EXPECT_EQ(j.shadow_map().bias_slope(), 0.0f);  // the JSON's shadow map has none
}

TEST(BuildRequest, SceneFlagReplacesTheJsonScene) {
  TempDir dir;
  RequestFlags f;
  f.request = dir.write("req.json", R"({"scene": {"meshes": [{}, {}], "instances": [{}]},
      "camera": {"eye": {"z": 1}, "target": {}}, "lights": [{"point": {}}]})")
                  .string();
  EXPECT_EQ(build_request(f).scene().meshes_size(), 2);  // no --scene: the JSON's
  f.scene = dir.write("tri.obj", kTriangleObj).string();
  EXPECT_EQ(build_request(f).scene().meshes_size(), 1);
}

TEST(BuildRequest, MissingOrBadInputNamesTheFlag) {
  TempDir dir;
  const std::string obj = dir.write("tri.obj", kTriangleObj).string();
  RequestFlags f;
  EXPECT_THAT(flag_error_of(f), HasSubstr("--scene: required"));
  f.scene = obj;
  EXPECT_THAT(flag_error_of(f), HasSubstr("--eye: required"));
  f.eye = "0,1,2";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--target: required"));
  f.target = "0,0,0";
  EXPECT_THAT(flag_error_of(f), HasSubstr("--light: required"));
  f.lights = {"directional:0,-1,0"};
  EXPECT_EQ(flag_error_of(f), "(no error)");

  // No --request was given: the messages do not blame one.
  for (const auto& [clear, flag] : {std::pair<void (*)(RequestFlags&), const char*>{
                                        [](RequestFlags& g) { g.eye.reset(); }, "--eye"},
                                    {[](RequestFlags& g) { g.target.reset(); }, "--target"},
                                    {[](RequestFlags& g) { g.lights.clear(); }, "--light"},
                                    {[](RequestFlags& g) { g.scene.reset(); }, "--scene"}}) {
    RequestFlags missing = f;
    clear(missing);
    EXPECT_THAT(flag_error_of(missing), HasSubstr(std::string(flag) + ": required: "));
    EXPECT_THAT(flag_error_of(missing), Not(HasSubstr("--request"))) << flag;
  }
  // With one, it lacks the field too.
  RequestFlags from_json;
  from_json.request = dir.write("empty.json", "{}").string();
  from_json.scene = obj;
  EXPECT_THAT(flag_error_of(from_json),
              HasSubstr("--eye: required: the camera's position X,Y,Z (builtin:demo brings its "
                        "own camera) (and --request " +
                        *from_json.request + " has none)"));

  RequestFlags bad = f;
  bad.near = "close";
  EXPECT_THAT(flag_error_of(bad), HasSubstr("--near: expected a finite number"));
  bad = f;
  bad.scene = (dir.path() / "absent.glb").string();
  EXPECT_THAT(flag_error_of(bad), HasSubstr("--scene: " + *bad.scene + ": no such file"));
  bad = f;
  bad.request = dir.write("bad.json", R"({"camera": {"eyes": {}}})").string();
  EXPECT_THAT(flag_error_of(bad),
              HasSubstr("--request: " + *bad.request + ": not a RenderRequest"));
  bad.request = (dir.path() / "absent.json").string();
  EXPECT_THAT(flag_error_of(bad), HasSubstr("--request: " + *bad.request + ": cannot open"));
}

// Issue 54: the server's own rules, checked before any connection, name the flag and the range;
// a field no flag sets is --request's; a scene the server holds is its to check.
TEST(CheckLikeTheServer, NamesTheFlagAndTheRange) {
  TempDir dir;
  RequestFlags f;
  f.scene = dir.write("tri.obj", kTriangleObj).string();
  f.eye = "0,5,5";
  f.target = "0,0,0";
  f.lights = {"directional:0,-1,0"};
  const auto error_of = [](const RequestFlags& g) -> std::string {
    try {
      check_like_the_server(build_request(g));
    } catch (const FlagError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(e.flag() + ": ", 0), 0u) << e.what();
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(error_of(f), "(no error)");
  RequestFlags bad = f;
  bad.map_size = "3";
  EXPECT_EQ(error_of(bad), "--map-size: shadow_map.size: must be in [256, 8192], got 3");
  bad = f;
  bad.size = "20000x10";
  EXPECT_EQ(error_of(bad), "--size: camera.width: must be in [1, 16384], got 20000");
  bad = f;
  bad.filter = "poisson";
  bad.pcf_taps = "65";
  EXPECT_EQ(error_of(bad), "--pcf-taps: filter.poisson.taps: must be 1..64, got 65");
  bad = f;
  bad.request = dir.write("depth.json", R"({"shadow_map": {"bias_slope": -1}})").string();
  EXPECT_THAT(error_of(bad), HasSubstr("--bias-slope: shadow_map.bias_slope: "));
  // By scene id: the scene's checks are the server's (here the id is not even well formed).
  RequestFlags by_id = f;
  by_id.scene.reset();
  by_id.scene_id = "not-an-id";
  EXPECT_EQ(error_of(by_id), "(no error)");
  by_id.scene = f.scene;
  EXPECT_THAT(flag_error_of(by_id), HasSubstr("--scene-id: not with --scene"));
}

// --size 0x0 was once read as "unset" and rendered 1280x720.
TEST(BuildRequest, ASizeOfZeroIsRefused) {
  for (const char* size : {"0x0", "0x720", "1280x0"}) {
    RequestFlags f;
    f.scene = "builtin:demo";
    f.size = size;
    EXPECT_THAT(flag_error_of(f),
                HasSubstr("--size: expected WxH with whole numbers of at least 1"))
        << size;
  }
}

}  // namespace
}  // namespace shadow::ctl
