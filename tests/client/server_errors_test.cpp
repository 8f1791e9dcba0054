// shadowctl's note on server errors: the proto fields and enum values the server names, as the
// flags and values a shadowctl user types.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "shadowctl/server_errors.hpp"
#include "wire/names.hpp"

namespace shadow::ctl {
namespace {

using grpc::StatusCode;
using ::testing::HasSubstr;
using ::testing::Not;

TEST(ServerErrors, FieldsMapToTheirFlags) {
  EXPECT_EQ(flag_for_field("shadow_map.size"), "--map-size");
  EXPECT_EQ(flag_for_field("shadow_map.fit"), "--fit");
  EXPECT_EQ(flag_for_field("camera.fov_deg"), "--fov");
  EXPECT_EQ(flag_for_field("camera.width"), "--size");
  EXPECT_EQ(flag_for_field("filter.poisson.taps"), "--pcf-taps");
  EXPECT_EQ(flag_for_field("filter.pcss_csm.terms"), "--csm-terms");
  EXPECT_EQ(flag_for_field("filter.blur"), "--filter blur");
  EXPECT_EQ(flag_for_field("atlas.tile_size"), "--atlas-tile");
  EXPECT_EQ(flag_for_field("products[2]"), "--products");
  EXPECT_EQ(flag_for_field("lights[0].size"), "--light-size");
  EXPECT_EQ(flag_for_field("lights[3].size"), "--light-size");
  EXPECT_EQ(flag_for_field("lights[0].spot.cone_angle_deg"),
            "--light spot:PX,PY,PZ:DX,DY,DZ:CONE_DEG");
  EXPECT_EQ(flag_for_field("lights[1].directional.direction"),
            "--light directional:DX,DY,DZ (--light number 2)");
  // The longest known prefix decides.
  EXPECT_EQ(flag_for_field("scene.meshes[3].indices[17]"), "--scene");
  EXPECT_EQ(flag_for_field("scene.instances[2].receiver_class"), "--receiver-class");
  EXPECT_THAT(flag_for_field("quality.max_error"), HasSubstr("--max-error (a percentage"));
  // A sequence: the base is the flags, a frame's fields its file.
  EXPECT_EQ(flag_for_field("base.shadow_map.technique"), "--technique");
  EXPECT_EQ(flag_for_field("frames[4].camera.eye"), "frame 4 of --frames");
  EXPECT_EQ(flag_for_field("scene_id"), "--scene-id");
  // No flag sets this.
  EXPECT_EQ(flag_for_field("shadow_mapping"), "");
}

// Every value shadowctl can spell is known by its proto name, from the one name table.
TEST(ServerErrors, EveryEnumValueMapsToItsFlagValue) {
  for (const auto& row : names::kTechniques.rows())
    EXPECT_EQ(flag_for_enum_value(v1::Technique_Name(row.proto)),
              "--technique " + std::string(row.name));
  for (const auto& row : names::kProducts.rows())
    EXPECT_EQ(flag_for_enum_value(v1::Product_Name(row.proto)),
              "--products " + std::string(row.name));
  EXPECT_EQ(flag_for_enum_value("MAP_FIT_SCENE"), "--fit scene");
  EXPECT_EQ(flag_for_enum_value("PSM_NEAR_VIRTUAL_SLIDE_BACK"), "--psm-near virtual-slide-back");
  EXPECT_EQ(flag_for_enum_value("CSM_LOOKUP_SAT"), "--csm-lookup sat");
  EXPECT_EQ(flag_for_enum_value("PIXEL_FORMAT_FLOAT16"), "--pixel-format float16");
  EXPECT_EQ(flag_for_enum_value("NOT_A_VALUE"), "");
}

// The messages the issue names, as the engine words them.
TEST(ServerErrors, TheNoteNamesTheFlagsAUserTyped) {
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT,
                      "shadow_map.fit: MAP_FIT_SCENE fits uniform maps and cubes only (PSM and "
                      "LiSPSM warp the map to the camera's view), and lights[0] takes another "
                      "technique"),
            " (shadowctl: shadow_map.fit is --fit; MAP_FIT_SCENE is --fit scene)");
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT,
                      "shadow_map.technique: TECHNIQUE_LISPSM needs a directional light (use "
                      "TECHNIQUE_PSM for spot and point lights)"),
            " (shadowctl: shadow_map.technique is --technique; TECHNIQUE_LISPSM is --technique "
            "lispsm; TECHNIQUE_PSM is --technique psm)");
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT, "lights[0].size: PCSS needs a light size > 0"),
            " (shadowctl: lights[0].size is --light-size)");
  EXPECT_EQ(flag_note(StatusCode::RESOURCE_EXHAUSTED,
                      "filter.csm.terms: 16 terms of a 8192^2 map need 1 bytes"),
            " (shadowctl: filter.csm.terms is --csm-terms)");
  // Virtual maps (issue 53): their settings, and the products and filters they refuse.
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT,
                      "shadow_map.virtual_pool_pages: must be in [1, 16384] pages of 128^2 "
                      "float32 texels (16384 pages = 1 GiB), got 0"),
            " (shadowctl: shadow_map.virtual_pool_pages is --virtual-pool-pages)");
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT,
                      "shadow_map.virtual_lod_bias: must be finite and in [-4, 4], got 5"),
            " (shadowctl: shadow_map.virtual_lod_bias is --virtual-lod-bias)");
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT,
                      "products[0]: PRODUCT_SHADOW_MAP is not available with TECHNIQUE_VIRTUAL"),
            " (shadowctl: products[0] is --products; PRODUCT_SHADOW_MAP is --products shadowmap; "
            "TECHNIQUE_VIRTUAL is --technique virtual)");
  // TECHNIQUE_PSM_CUBE is one name, not TECHNIQUE_PSM followed by more.
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT, "products[0]: TECHNIQUE_PSM_CUBE x"),
            " (shadowctl: products[0] is --products; TECHNIQUE_PSM_CUBE is --technique psm_cube)");
}

// UV errors suggest the server's own layout, unless the message does already.
TEST(ServerErrors, UvErrorsSuggestGeneratedUvs) {
  const std::string overlap =
      "scene.meshes[2].uvs: UV triangles overlap (5 texels covered twice over the atlas, whose "
      "tiles are 64x64 texels; the first at uv (0.5, 0.5) in instance 0's tile): the shadow "
      "atlas needs a unique layout (mirrored or tiled UVs are not one)";
  EXPECT_THAT(flag_note(StatusCode::INVALID_ARGUMENT, overlap),
              HasSubstr("--atlas-generate-uvs has the server lay out every receiving mesh"));
  EXPECT_THAT(flag_note(StatusCode::INVALID_ARGUMENT, overlap),
              HasSubstr("scene.meshes[2].uvs is --scene"));
  const std::string degenerate =
      "scene.meshes[0].uvs: every UV triangle has zero area: give the mesh a layout, or let the "
      "server make one (atlas.generate_uvs; shadowctl: --atlas-generate-uvs)";
  EXPECT_THAT(flag_note(StatusCode::INVALID_ARGUMENT, degenerate),
              Not(HasSubstr("--atlas-generate-uvs")));
  // Too many triangles to lay out: generating the layout would not help.
  EXPECT_THAT(flag_note(StatusCode::RESOURCE_EXHAUSTED,
                        "scene.meshes[0].uvs: absent, and the mesh's 30000 triangles are over"),
              Not(HasSubstr("--atlas-generate-uvs")));
}

TEST(ServerErrors, NothingToSayIsNothing) {
  // The engine's message already names the flag.
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT,
                      "shadow_map.fit: the shadow atlas needs maps fitted to the scene "
                      "(MAP_FIT_SCENE; shadowctl: --fit scene): it covers every receiver"),
            "");
  EXPECT_EQ(flag_note(StatusCode::NOT_FOUND, "scene_id: no such scene"), "");
  EXPECT_EQ(flag_note(StatusCode::UNAVAILABLE, "shadow_map.size: down"), "");
  EXPECT_EQ(flag_note(StatusCode::INVALID_ARGUMENT, "the request was refused: reasons"), "");
}

}  // namespace
}  // namespace shadow::ctl
