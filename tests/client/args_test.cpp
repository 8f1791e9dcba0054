// shadowctl's flag parsers: values come out exact, and every error names its flag.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "shadowctl/args.hpp"

namespace shadow::ctl {
namespace {

using ::testing::HasSubstr;

template <class F>
std::string error_of(F&& parse) {
  try {
    parse();
  } catch (const FlagError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Args, Numbers) {
  EXPECT_EQ(parse_float("0.25", "--fov"), 0.25f);
  EXPECT_EQ(parse_float("-3", "--fov"), -3.0f);
  EXPECT_EQ(parse_float("1e-4", "--fov"), 1e-4f);
  EXPECT_EQ(parse_uint("4096", "--map-size"), 4096u);
  for (const char* bad : {"", "abc", "1.5x", "nan", "inf", " 1"})
    EXPECT_THAT(error_of([&] { parse_float(bad, "--fov"); }), HasSubstr("--fov: expected")) << bad;
  for (const char* bad : {"", "-1", "1.5", "4294967296", "12k"})
    EXPECT_THAT(error_of([&] { parse_uint(bad, "--map-size"); }), HasSubstr("--map-size: ")) << bad;
}

TEST(Args, Vectors) {
  EXPECT_EQ(parse_vec3("1,-2.5,3e1", "--eye"), glm::vec3(1, -2.5f, 30));
  for (const char* bad : {"1,2", "1,2,3,4", "1,,3", "a,b,c", ""})
    EXPECT_THAT(error_of([&] { parse_vec3(bad, "--eye"); }), HasSubstr("--eye: expected X,Y,Z"))
        << bad;
}

TEST(Args, Sizes) {
  const ImageSize s = parse_size("1280x720", "--size");
  EXPECT_EQ(s.width, 1280u);
  EXPECT_EQ(s.height, 720u);
  EXPECT_EQ(parse_size("64X32", "--size").height, 32u);
  for (const char* bad : {"1280", "1280x", "x720", "12.5x3", "1280*720"})
    EXPECT_THAT(error_of([&] { parse_size(bad, "--size"); }), HasSubstr("--size: expected WxH"))
        << bad;
}

TEST(Args, Lights) {
  const Light d = parse_light("directional:0.5,-1,0", "--light");
  EXPECT_EQ(d.type, LightType::kDirectional);
  EXPECT_EQ(d.direction, glm::vec3(0.5f, -1, 0));

  const Light s = parse_light("spot:1,2,3:0,-1,0:40", "--light");
  EXPECT_EQ(s.type, LightType::kSpot);
  EXPECT_EQ(s.position, glm::vec3(1, 2, 3));
  EXPECT_EQ(s.direction, glm::vec3(0, -1, 0));
  EXPECT_EQ(s.cone_angle_deg, 40.0f);

  const Light p = parse_light("point:4,5,6", "--light");
  EXPECT_EQ(p.type, LightType::kPoint);
  EXPECT_EQ(p.position, glm::vec3(4, 5, 6));
  EXPECT_EQ(p.size, 0.0f);

  EXPECT_THAT(error_of([] { parse_light("sun:0,-1,0", "--light"); }),
              HasSubstr("--light: unknown light kind 'sun'"));
  EXPECT_THAT(error_of([] { parse_light("spot:1,2,3:0,-1,0", "--light"); }),
              HasSubstr("--light: expected spot:PX,PY,PZ:DX,DY,DZ:CONE_DEG"));
  EXPECT_THAT(error_of([] { parse_light("point:1,2", "--light"); }),
              HasSubstr("--light: expected X,Y,Z"));
  EXPECT_THAT(error_of([] { parse_light("directional", "--light"); }),
              HasSubstr("--light: expected directional:DX,DY,DZ"));
}

TEST(Args, ProductsAndTechnique) {
  EXPECT_EQ(parse_products("visibility,shadowmap", "--products"),
            (std::vector<Product>{Product::kVisibility, Product::kShadowMap}));
  EXPECT_EQ(parse_products("position", "--products"), std::vector<Product>{Product::kPosition});
  EXPECT_THAT(error_of([] { parse_products("shadowmap,depth", "--products"); }),
              HasSubstr("--products: unknown product 'depth'"));
  EXPECT_THAT(error_of([] { parse_products("position,position", "--products"); }),
              HasSubstr("--products: 'position' is listed twice"));
  EXPECT_THAT(error_of([] { parse_products("", "--products"); }),
              HasSubstr("--products: unknown product ''"));
  EXPECT_EQ(parse_technique("uniform", "--technique"), Technique::kUniform);
  EXPECT_EQ(parse_technique("psm", "--technique"), Technique::kPsm);
  EXPECT_EQ(parse_technique("lispsm", "--technique"), Technique::kLispsm);
  EXPECT_THAT(error_of([] { parse_technique("tsm", "--technique"); }),
              HasSubstr("--technique: unknown technique 'tsm'"));
  EXPECT_EQ(parse_psm_casters("slide-back", "--psm-casters"), PsmCasters::kSlideBack);
  EXPECT_EQ(parse_psm_casters("inverse-projection", "--psm-casters"),
            PsmCasters::kInverseProjection);
  EXPECT_EQ(parse_psm_near("camera", "--psm-near"), PsmNear::kCamera);
  EXPECT_THAT(error_of([] { parse_psm_near("far", "--psm-near"); }),
              HasSubstr("--psm-near: unknown mode 'far'"));
}

}  // namespace
}  // namespace shadow::ctl
