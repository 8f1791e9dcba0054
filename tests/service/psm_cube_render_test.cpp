// PSM_CUBE through the real server and client: a light facing the camera gets a cube texture
// "shadowmap_cube" whose faces match the header's face report, with the texel-size range; a sun
// parallel to the image plane in post-perspective space gets the one ordinary PSM map and says
// so; PCSS is refused as for PSM and cube maps.
#include <algorithm>
#include <string>

#include "server_fixture.hpp"
#include "test_scene.hpp"

namespace shadow::test {
namespace {

using PsmCubeRender = ServerFixture<>;

// tiny_proto_request (camera at (0, 6, 12) looking at the origin) with a sun along `direction`,
// TECHNIQUE_PSM_CUBE and the shadow map among the products.
v1::RenderRequest psm_cube_request(float dx, float dy, float dz) {
  v1::RenderRequest r = tiny_proto_request();
  v1::Vec3* d = r.mutable_lights(0)->mutable_directional()->mutable_direction();
  d->set_x(dx);
  d->set_y(dy);
  d->set_z(dz);
  r.mutable_shadow_map()->set_technique(v1::TECHNIQUE_PSM_CUBE);
  r.clear_products();
  r.add_products(v1::PRODUCT_SHADOW_MAP);
  r.add_products(v1::PRODUCT_VISIBILITY);
  return r;
}

TEST_F(PsmCubeRender, LightFacingTheCameraGetsACube) {
  auto c = client();
  // Travelling towards the camera (+z) and down onto the ground.
  const v1::RenderRequest r = psm_cube_request(0.1f, -0.5f, 1.0f);
  const RenderResult res = c.render(r);
  std::printf("[ psm cube ] %s: texels %g .. %g\n", res.light_fits[0].light_case.c_str(),
              res.light_fits[0].cube_texel_min, res.light_fits[0].cube_texel_max);
  ASSERT_EQ(res.textures.size(), 2u);
  const Texture& cube = res.textures[0];
  EXPECT_EQ(cube.name, "shadowmap_cube");
  EXPECT_EQ(cube.width, r.shadow_map().size());
  EXPECT_EQ(cube.height, r.shadow_map().size());
  ASSERT_EQ(res.light_fits[0].cube_faces.size(), 6u);
  const auto rendered =
      std::count_if(res.light_fits[0].cube_faces.begin(), res.light_fits[0].cube_faces.end(),
                    [](const CubeFaceReport& f) { return f.rendered; });
  EXPECT_GE(rendered, 1);
  EXPECT_EQ(cube.faces, uint32_t(rendered));
  ASSERT_EQ(cube.cube_faces.size(), cube.faces);
  for (const TextureFace& face : cube.cube_faces) {
    const auto report =
        std::find_if(res.light_fits[0].cube_faces.begin(), res.light_fits[0].cube_faces.end(),
                     [&](const CubeFaceReport& f) { return f.name == face.name; });
    ASSERT_NE(report, res.light_fits[0].cube_faces.end()) << face.name;
    EXPECT_TRUE(report->rendered) << face.name;
  }
  EXPECT_GT(res.light_fits[0].cube_texel_min, 0.0);
  EXPECT_LE(res.light_fits[0].cube_texel_min, res.light_fits[0].cube_texel_max);
  EXPECT_LT(res.light_fits[0].cube_texel_max, 1.0);
  EXPECT_FALSE(res.light_fits[0].light_case.empty());
  EXPECT_EQ(res.textures[1].name, "visibility");
}

TEST_F(PsmCubeRender, SunParallelToTheImagePlaneGetsOneMap) {
  auto c = client();
  // (0, -2, 1) is perpendicular to the view direction (0, -6, -12): PSM's directional case.
  const RenderResult res = c.render(psm_cube_request(0.0f, -2.0f, 1.0f));
  std::printf("[ psm cube ] %s\n", res.light_fits[0].light_case.c_str());
  ASSERT_EQ(res.textures.size(), 2u);
  EXPECT_EQ(res.textures[0].name, "shadowmap");
  EXPECT_EQ(res.textures[0].faces, 1u);
  EXPECT_TRUE(res.textures[0].cube_faces.empty());
  EXPECT_TRUE(res.light_fits[0].cube_faces.empty());
  EXPECT_EQ(res.light_fits[0].cube_texel_min, 0.0);
  EXPECT_EQ(res.light_fits[0].cube_texel_max, 0.0);
  EXPECT_NE(res.light_fits[0].light_case.find("parallel"), std::string::npos)
      << res.light_fits[0].light_case;
}

TEST_F(PsmCubeRender, PcssIsRefused) {
  auto c = client();
  v1::RenderRequest r = psm_cube_request(0.1f, -0.5f, 1.0f);
  r.mutable_lights(0)->set_size(1.0f);
  r.mutable_filter()->mutable_pcss();
  try {
    c.render(r);
    ADD_FAILURE() << "accepted PSM_CUBE with pcss";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT) << e.what();
    const std::string what = e.what();
    EXPECT_TRUE(what.rfind("shadow_map.technique: ", 0) == 0 || what.rfind("filter.pcss: ", 0) == 0)
        << what;
  }
}

}  // namespace
}  // namespace shadow::test
