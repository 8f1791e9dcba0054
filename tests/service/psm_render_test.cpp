// PSM through the real server: the reply reports the case and finite effective parameters, and
// spot lights render; what PSM does not support yet (point lights, PCSS) is rejected with
// INVALID_ARGUMENT naming shadow_map.technique.
#include <cmath>
#include <string>

#include "server_fixture.hpp"
#include "test_scene.hpp"

namespace shadow::test {
namespace {

using PsmRender = ServerFixture<>;

TEST_F(PsmRender, ReportsTheCaseAndTheEffectiveParameters) {
  auto c = client();
  v1::RenderRequest r = tiny_proto_request();
  r.mutable_shadow_map()->set_technique(v1::TECHNIQUE_PSM);
  const RenderResult res = c.render(r);
  std::printf("[ psm      ] %s: virtual near %g far %g, light near %g far %g, slide %g\n",
              res.light_fits[0].light_case.c_str(), res.light_fits[0].virtual_near,
              res.light_fits[0].virtual_far, res.light_fits[0].light_near,
              res.light_fits[0].light_far, res.light_fits[0].slide_back);
  EXPECT_NE(res.light_fits[0].light_case.find("directional"), std::string::npos);
  EXPECT_GT(res.light_fits[0].virtual_far, res.light_fits[0].virtual_near);
  EXPECT_GT(res.light_fits[0].virtual_near, 0.0);
  for (double v : {res.light_fits[0].light_near, res.light_fits[0].light_far})
    EXPECT_TRUE(std::isfinite(v));
  r.mutable_shadow_map()->set_technique(v1::TECHNIQUE_UNIFORM);
  EXPECT_EQ(c.render(r).light_fits[0].light_case, "uniform: directional");
}

TEST_F(PsmRender, SpotAndPointLightsRenderPcssIsRejected) {
  auto c = client();
  v1::RenderRequest r = tiny_proto_request();
  r.mutable_shadow_map()->set_technique(v1::TECHNIQUE_PSM);
  v1::RenderRequest spot = r;
  v1::SpotLight* s = spot.mutable_lights(0)->mutable_spot();
  s->mutable_position()->set_y(10);
  s->mutable_direction()->set_y(-1);
  s->set_cone_angle_deg(60);
  const RenderResult res = c.render(spot);
  EXPECT_EQ(res.light_fits[0].light_case.rfind("spot ", 0), 0u) << res.light_fits[0].light_case;
  v1::RenderRequest point = r;
  point.mutable_lights(0)->mutable_point()->mutable_position()->set_y(10);
  const RenderResult p = c.render(point);
  EXPECT_EQ(p.light_fits[0].light_case.rfind("point ", 0), 0u) << p.light_fits[0].light_case;
  v1::RenderRequest pcss = r;
  pcss.mutable_lights(0)->set_size(1.0f);
  pcss.mutable_filter()->mutable_pcss();
  try {
    c.render(pcss);
    ADD_FAILURE() << "accepted";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("shadow_map.technique: ", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace shadow::test
