// Mip chains as one multi-part EXR and float64 SATs as hi + lo float32 channels.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include "output/levels_writer.hpp"
#include "output/write_products.hpp"
#include "temp_dir.hpp"

namespace shadow::output {
namespace {

Texture level(uint32_t i, uint32_t w, uint32_t h) {
  Texture t;
  t.name = "visibility_mip" + std::to_string(i);
  t.kind = Product::kVisibilityMips;
  t.width = w;
  t.height = h;
  t.data.assign(size_t{w} * h, 0.25f * float(i));
  return t;
}

TEST(LevelsOutput, MipChainIsOneExrWithAPartPerLevel) {
  shadow::testing::TempDir dir;
  const std::vector<Texture> ts = {level(0, 5, 3), level(1, 2, 1), level(2, 1, 1)};
  const auto written = write_products(ts, dir.path());
  ASSERT_EQ(written.size(), 2u);
  EXPECT_EQ(written[0].path.filename(), "visibility_mips.exr");
  EXPECT_EQ(written[1].path.filename(), "visibility_mips.png");
  auto in = OIIO::ImageInput::open(written[0].path.string());
  ASSERT_TRUE(in);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(in->seek_subimage(i, 0)) << i;
    EXPECT_EQ(uint32_t(in->spec().width), ts[i].width);
    EXPECT_EQ(uint32_t(in->spec().height), ts[i].height);
    std::vector<float> px(ts[i].data.size());
    ASSERT_TRUE(in->read_image(i, 0, 0, 1, OIIO::TypeDesc::FLOAT, px.data()));
    EXPECT_EQ(px, ts[i].data);
  }
  EXPECT_FALSE(in->seek_subimage(3, 0));
}

TEST(LevelsOutput, Float64SatIsHiPlusLoFloat32) {
  Texture t;
  t.name = "shadowmap_sat";
  t.kind = Product::kShadowMapSat;
  t.width = 3;
  t.height = 2;
  t.format = PixelFormat::kFloat64;
  t.data64 = {1.0, 16777217.0, 123456789.123456789, 1e-9, 0.1, 4194303.999999};
  shadow::testing::TempDir dir;
  const auto written = write_products({t}, dir.path());
  auto in = OIIO::ImageInput::open(written[0].path.string());
  ASSERT_TRUE(in);
  ASSERT_EQ(in->spec().nchannels, 2);
  EXPECT_EQ(in->spec().channelnames[0], "S.hi");
  EXPECT_EQ(in->spec().channelnames[1], "S.lo");
  std::vector<float> px(12);
  ASSERT_TRUE(in->read_image(0, 0, 0, 2, OIIO::TypeDesc::FLOAT, px.data()));
  for (size_t i = 0; i < 6; ++i) {
    const double v = double(px[2 * i]) + double(px[2 * i + 1]);
    EXPECT_NEAR(v, t.data64[i], std::abs(t.data64[i]) * 1e-14) << i;
  }
}

}  // namespace
}  // namespace shadow::output
