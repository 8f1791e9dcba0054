// shadowctl and cube maps: --technique cube, a point light without --technique leaves the
// technique to the server (which picks cube), an explicit technique is sent as given, and the
// report lists the cube faces and a cube with no face.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "shadowctl/args.hpp"
#include "shadowctl/report.hpp"
#include "shadowctl/request.hpp"
#include "temp_dir.hpp"

namespace shadow::ctl {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

TEST(CubeFlags, TechniqueCube) {
  EXPECT_EQ(parse_technique("cube", "--technique"), Technique::kCube);
  EXPECT_EQ(parse_technique("psm_cube", "--technique"), Technique::kPsmCube);
  EXPECT_THROW(parse_technique("psm-cube", "--technique"), FlagError);
  try {
    parse_technique("cubemap", "--technique");
    FAIL() << "accepted 'cubemap'";
  } catch (const FlagError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--technique: unknown technique 'cubemap' (expected uniform, "
                                    "psm, cube, psm_cube, lispsm, auto or virtual)"));
  }
  RequestFlags f;
  f.scene = kDemoScene;
  f.lights = {"point:0,3,0"};
  f.technique = "cube";
  EXPECT_EQ(build_request(f).shadow_map().technique(), v1::TECHNIQUE_CUBE);
}

TEST(CubeFlags, PointLightWithoutTechniqueLeavesItToTheServer) {
  RequestFlags f;
  f.scene = kDemoScene;  // its suggested shadow-map settings name no technique
  f.lights = {"point:0,3,0"};
  v1::RenderRequest r = build_request(f);
  ASSERT_TRUE(r.lights(0).has_point());
  EXPECT_EQ(r.lights(0).point().position().y(), 3.0f);
  EXPECT_EQ(r.shadow_map().technique(), v1::TECHNIQUE_UNSPECIFIED);
  EXPECT_GT(r.shadow_map().bias_slope(), 0.0f);  // the demo's biases are still suggested

  // The same for the demo's own directional light: the server picks uniform.
  f.lights.clear();
  r = build_request(f);
  ASSERT_TRUE(r.lights(0).has_directional());
  EXPECT_EQ(r.shadow_map().technique(), v1::TECHNIQUE_UNSPECIFIED);
}

TEST(CubeFlags, TechniqueFromTheRequestIsSentAsGiven) {
  shadow::testing::TempDir dir;
  RequestFlags f;
  f.scene = kDemoScene;
  f.request =
      dir.write("req.json", R"({"shadowMap": {"technique": "TECHNIQUE_UNIFORM"}})").string();
  f.lights = {"point:0,3,0"};
  // Not changed behind the user's back: the server refuses uniform for a point light.
  EXPECT_EQ(build_request(f).shadow_map().technique(), v1::TECHNIQUE_UNIFORM);
  f.request = dir.write("cube.json", R"({"shadowMap": {"technique": "TECHNIQUE_CUBE"}})").string();
  EXPECT_EQ(build_request(f).shadow_map().technique(), v1::TECHNIQUE_CUBE);
}

TEST(CubeReport, ListsEveryFaceAndTheCubeFile) {
  RenderResult r;
  r.light_fits.resize(1);
  Texture cube;
  cube.name = "shadowmap_cube";
  cube.width = cube.height = 512;
  cube.faces = 2;
  cube.cube_faces = {{"+x", {}, {}}, {"-y", {}, {}}};
  r.textures.push_back(cube);
  r.light_fits[0].light_case = "cube: point light";
  for (const char* face : {"+x", "-x", "+y", "-y", "+z", "-z"}) {
    const bool rendered = face == std::string("+x") || face == std::string("-y");
    r.light_fits[0].cube_faces.push_back(
        {face, rendered, rendered ? "2 casters in front of 1 visible receiver" : "no receiver"});
  }
  const std::vector<output::WrittenFile> files = {{"out/shadowmap_cube.exr", &r.textures[0], 2048},
                                                  {"out/shadowmap_cube.png", &r.textures[0], 512}};
  const std::string report = format_report(r, files, Timeline{});
  EXPECT_THAT(report, HasSubstr("512x512, 1 channel float32, 2 faces"));
  EXPECT_THAT(report, HasSubstr("512x1024 preview"));
  EXPECT_THAT(report, HasSubstr("light: cube: point light\n  cube: 2 of 6 faces rendered\n"));
  EXPECT_THAT(report, HasSubstr("    +x  rendered  2 casters in front of 1 visible receiver\n"));
  EXPECT_THAT(report, HasSubstr("    -x  skipped   no receiver\n"));
  EXPECT_THAT(report, HasSubstr("    -z  skipped   no receiver\n"));
  EXPECT_THAT(report, Not(HasSubstr("no cube face rendered")));
}

TEST(CubeReport, SaysWhenNoFaceWasRendered) {
  RenderResult r;
  r.light_fits.resize(1);
  Texture cube;
  cube.name = "shadowmap_cube";
  cube.faces = 0;
  r.textures.push_back(cube);
  r.light_fits[0].light_case = "cube: point light";
  for (const char* face : {"+x", "-x", "+y", "-y", "+z", "-z"})
    r.light_fits[0].cube_faces.push_back({face, false, "no visible receiver"});
  const std::string report = format_report(r, {}, Timeline{});
  EXPECT_THAT(report, HasSubstr("(shadowmap_cube: no cube face rendered, no file written)"));
  EXPECT_THAT(report, HasSubstr("cube: 0 of 6 faces rendered"));
}

TEST(CubeReport, NoCubeNoFaceLines) {
  RenderResult r;
  r.light_fits.resize(1);
  r.light_fits[0].light_case = "uniform: directional";
  const std::string report = format_report(r, {}, Timeline{});
  EXPECT_THAT(report, HasSubstr("light: uniform: directional\n"));
  EXPECT_THAT(report, Not(HasSubstr("cube")));
}

}  // namespace
}  // namespace shadow::ctl
