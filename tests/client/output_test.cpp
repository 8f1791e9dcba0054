// Writes textures, reads them back with OpenImageIO, and checks pixels, channels and the
// matrices' row-vector convention.
#include <algorithm>
#include <cmath>
#include <limits>

#include <OpenImageIO/imageio.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "exr_matrix.hpp"
#include "output/png_preview.hpp"
#include "output/write_products.hpp"
#include "temp_dir.hpp"

namespace shadow::output {
namespace {

using shadow::testing::matrix;
using shadow::testing::row_times;
using shadow::testing::TempDir;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Image {
  OIIO::ImageSpec spec;
  std::vector<float> floats;
  std::vector<uint8_t> bytes;
};

Image read(const std::filesystem::path& file) {
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) throw std::runtime_error("cannot open " + file.string() + ": " + OIIO::geterror());
  Image img{in->spec(), {}, {}};
  const size_t n = img.spec.image_pixels() * img.spec.nchannels;
  if (img.spec.format == OIIO::TypeDesc::UINT8) {
    img.bytes.resize(n);
    in->read_image(0, 0, 0, img.spec.nchannels, OIIO::TypeDesc::UINT8, img.bytes.data());
  } else {
    img.floats.resize(n);
    in->read_image(0, 0, 0, img.spec.nchannels, OIIO::TypeDesc::FLOAT, img.floats.data());
  }
  return img;
}

// A spot light's texture matrix: perspective, so w varies and a transposed matrix shows.
Texture shadow_map_texture() {
  Texture t;
  t.name = "shadowmap";
  t.kind = Product::kShadowMap;
  t.width = 8;
  t.height = 4;
  t.world_to_camera = glm::lookAt(glm::vec3(3, 10, 2), glm::vec3(0, 0, 0), glm::vec3(0, 0, -1));
  const glm::mat4 ndc_to_uv =  // x, y: [-1,1] → [0,1] with y down; z kept
      glm::translate(glm::mat4(1.0f), glm::vec3(0.5f, 0.5f, 0)) *
      glm::scale(glm::mat4(1.0f), glm::vec3(0.5f, -0.5f, 1));
  t.world_to_ndc =
      ndc_to_uv * glm::perspective(glm::radians(70.0f), 2.0f, 1.0f, 30.0f) * t.world_to_camera;
  for (uint32_t i = 0; i < t.width * t.height; ++i) t.data.push_back(0.5f + i / 64.0f);
  t.data[5] = 1.0f;  // cleared texel
  return t;
}

TEST(WriteProducts, ShadowMapKeepsDepthsChannelAndMatrices) {
  TempDir dir;
  const Texture t = shadow_map_texture();
  const auto written = write_products({t}, dir.path() / "nested" / "out");
  ASSERT_EQ(written.size(), 2u);
  EXPECT_EQ(written[0].path, dir.path() / "nested/out/shadowmap.exr");
  EXPECT_EQ(written[1].path, dir.path() / "nested/out/shadowmap.png");
  EXPECT_GT(written[0].bytes, 0u);

  const Image img = read(written[0].path);
  EXPECT_EQ(img.spec.width, 8);
  EXPECT_EQ(img.spec.height, 4);
  EXPECT_EQ(img.spec.format, OIIO::TypeDesc::FLOAT);
  EXPECT_EQ(img.spec.channelnames, std::vector<std::string>{"Z"});
  EXPECT_EQ(img.floats, t.data);
  EXPECT_EQ(img.spec.get_string_attribute("textureformat"), "Shadow");

  // Every texel centre, unprojected through the engine's matrix, comes back to that texel when
  // multiplied as p · M by the stored worldtoNDC, at the same depth.
  const auto m = matrix(img.spec, "worldtoNDC");
  const glm::mat4 ndc_to_world = glm::inverse(t.world_to_ndc);
  for (uint32_t j = 0; j < t.height; ++j)
    for (uint32_t i = 0; i < t.width; ++i) {
      const glm::vec4 uvz((i + 0.5f) / t.width, (j + 0.5f) / t.height, 0.7f, 1);
      glm::vec4 world = ndc_to_world * uvz;
      world /= world.w;
      const glm::vec4 q = row_times(world, m);
      EXPECT_EQ(static_cast<int>(std::floor(q.x / q.w * t.width)), static_cast<int>(i));
      EXPECT_EQ(static_cast<int>(std::floor(q.y / q.w * t.height)), static_cast<int>(j));
      EXPECT_NEAR(q.z / q.w, 0.7f, 1e-4f);
    }

  // worldtocamera in the same convention: the light position maps to the view-space origin.
  const glm::vec4 eye = row_times(glm::vec4(3, 10, 2, 1), matrix(img.spec, "worldtocamera"));
  EXPECT_NEAR(glm::length(glm::vec3(eye)), 0.0f, 1e-5f);
  EXPECT_NEAR(eye.w, 1.0f, 1e-6f);
  const glm::vec4 target = row_times(glm::vec4(0, 0, 0, 1), matrix(img.spec, "worldtocamera"));
  EXPECT_NEAR(target.z, -glm::length(glm::vec3(3, 10, 2)), 1e-4f);  // looks down -z

  // Preview, grey so with one channel: nearest depth black, farthest drawn depth white, cleared
  // texel white, and between them std::lround of the float product, every one.
  const Image png = read(written[1].path);
  ASSERT_EQ(png.spec.nchannels, 1);
  EXPECT_EQ(png.bytes[0], 0);
  EXPECT_EQ(png.bytes[31], 255);
  EXPECT_EQ(png.bytes[5], 255);
  EXPECT_EQ(png.bytes[4], static_cast<uint8_t>(std::lround(4.0 / 31 * 255)));
  const float lo = t.data[0], hi = t.data[31];
  for (int i = 0; i < 32; ++i) {
    if (i == 5) continue;
    EXPECT_EQ(png.bytes[i], std::lround((t.data[i] - lo) / (hi - lo) * 255.0f)) << i;
  }
}

TEST(WriteProducts, VisibilityKeepsNaNAndPreviewMarksIt) {
  TempDir dir;
  Texture t;
  t.name = "visibility";
  t.kind = Product::kVisibility;
  t.width = 3;
  t.height = 2;
  t.data = {1, 0, 0.5f, kNaN, 1, kNaN};
  const auto written = write_products({t}, dir.path());
  const Image img = read(written[0].path);
  EXPECT_EQ(img.spec.channelnames, std::vector<std::string>{"Y"});
  EXPECT_EQ(img.spec.get_string_attribute("textureformat"), "");
  ASSERT_EQ(img.floats.size(), 6u);
  EXPECT_EQ(img.floats[0], 1.0f);
  EXPECT_EQ(img.floats[2], 0.5f);
  EXPECT_TRUE(std::isnan(img.floats[3]));
  EXPECT_TRUE(std::isnan(img.floats[5]));

  const Image png = read(written[1].path);  // RGB: the holes are coloured
  const std::vector<uint8_t> grey_and_nothing = {255, 255, 255, 0,   0,   0,   128, 128, 128,
                                                 64,  96,  160, 255, 255, 255, 64,  96,  160};
  EXPECT_EQ(png.bytes, grey_and_nothing);
}

// A preview is at most kPreviewEdge pixels across by default (every k-th texel of each face), and
// one per texel with Preview::kFull; the EXR keeps every texel either way.
TEST(WriteProducts, PreviewsAreAtMostKPreviewEdgeAcross) {
  TempDir dir;
  Texture t;
  t.name = "visibility";
  t.kind = Product::kVisibility;
  t.width = 2 * kPreviewEdge + 1;  // k = 3: 683 pixels across
  t.height = 5;
  for (uint32_t i = 0; i < t.width * t.height; ++i) t.data.push_back(float(i % t.width % 2));
  auto written = write_products({t}, dir.path());
  EXPECT_EQ(read(written[0].path).spec.width, int(t.width));
  const Image png = read(written[1].path);
  EXPECT_EQ(png.spec.width, 683);
  EXPECT_EQ(png.spec.height, 2);
  // Texels 0, 3, 6, ... of rows 0 and 3: 0, 1, 0, ...
  ASSERT_EQ(png.spec.nchannels, 1);  // grey
  for (int x = 0; x < 6; ++x) EXPECT_EQ(png.bytes[x], x % 2 ? 255 : 0) << x;
  OutputOptions full;
  full.preview = Preview::kFull;
  written = write_products({t}, dir.path(), full);
  EXPECT_EQ(read(written[1].path).spec.width, int(t.width));
  OutputOptions none;
  none.preview = Preview::kNone;
  EXPECT_EQ(write_products({t}, dir.path(), none).size(), 1u);
}

TEST(WriteProducts, PositionIsRgbWithNaNHoles) {
  TempDir dir;
  Texture t;
  t.name = "position";
  t.kind = Product::kPosition;
  t.width = 2;
  t.height = 2;
  t.channels = 3;
  t.data = {0, 10, -5, /**/ 2, 20, 5, /**/ kNaN, kNaN, kNaN, /**/ 1, 15, 0};
  const auto written = write_products({t}, dir.path());
  const Image img = read(written[0].path);
  EXPECT_EQ(img.spec.channelnames, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_EQ(img.floats[3], 2.0f);
  EXPECT_EQ(img.floats[5], 5.0f);
  EXPECT_TRUE(std::isnan(img.floats[7]));

  // Each channel normalized on its own: min → 0, max → 255, the middle → 128.
  const Image png = read(written[1].path);
  EXPECT_EQ(png.bytes, (std::vector<uint8_t>{0, 0, 0, 255, 255, 255, 64, 96, 160, 128, 128, 128}));
}

TEST(WriteProducts, CsmBasisHasNamedChannelsAndItsMapping) {
  TempDir dir;
  Texture t = shadow_map_texture();
  t.name = "csm_basis";
  t.kind = Product::kCsmBasis;
  t.channels = 5;  // M = 1 with the blocker channels
  t.channel_names = {"sin1", "cos1", "zsin1", "zcos1", "z"};
  t.depth_mapping = "linear: z = NDC z (orthographic), the distance from the near plane over 20";
  t.csm_terms = 1;
  t.csm_storage = CsmStorage::kFloat16;
  t.data.clear();
  for (uint32_t i = 0; i < t.width * t.height * t.channels; ++i) t.data.push_back(i * 0.25f);
  const auto written = write_products({t}, dir.path());
  ASSERT_EQ(written[0].path.filename(), "csm_basis.exr");
  const Image img = read(written[0].path);
  // EXR stores channels sorted by name: each one keeps its name and its values.
  ASSERT_EQ(img.spec.nchannels, 5);
  for (int c = 0; c < 5; ++c) {
    const auto at =
        std::find(t.channel_names.begin(), t.channel_names.end(), img.spec.channelnames[c]);
    ASSERT_NE(at, t.channel_names.end()) << img.spec.channelnames[c];
    const size_t src = at - t.channel_names.begin();
    for (size_t p = 0; p < size_t{t.width} * t.height; ++p)
      EXPECT_EQ(img.floats[p * 5 + c], t.data[p * 5 + src]) << img.spec.channelnames[c];
  }
  EXPECT_EQ(img.spec.get_string_attribute("shadow:depth_mapping"), t.depth_mapping);
  EXPECT_EQ(img.spec.get_int_attribute("shadow:csm_terms"), 1);
  EXPECT_EQ(img.spec.get_string_attribute("shadow:csm_storage"), "float16");
  const auto m = matrix(img.spec, "worldtoNDC");  // row-vector: GLM's column-major memory
  EXPECT_TRUE(std::equal(m.begin(), m.end(), &t.world_to_ndc[0][0]));
}

// A float16 texture is stored as HALF channels, every value kept.
TEST(WriteProducts, Float16IsWrittenAsHalf) {
  TempDir dir;
  Texture t = shadow_map_texture();
  t.format = PixelFormat::kFloat16;
  t.data16.clear();
  for (float v : t.data)
    t.data16.push_back(v == 1.0f ? 0x3c00 : uint16_t(0x3800 + t.data16.size()));
  t.data16[2] = 0x7e00;  // NaN
  t.data.clear();
  const auto written = write_products({t}, dir.path());
  ASSERT_EQ(written.size(), 2u);
  const Image img = read(written[0].path);
  EXPECT_EQ(img.spec.format, OIIO::TypeDesc::HALF);
  ASSERT_EQ(img.floats.size(), t.data16.size());
  for (size_t i = 0; i < t.data16.size(); ++i) {
    if (i == 2) {
      EXPECT_TRUE(std::isnan(img.floats[i]));
      continue;
    }
    const uint16_t h = t.data16[i];  // 0x38xx: 0.5 + (h & 0x3ff) / 2048; 0x3c00: 1
    const float want = h == 0x3c00 ? 1.0f : 0.5f + float(h & 0x3ff) / 2048.0f;
    EXPECT_EQ(img.floats[i], want) << i;
  }
}

TEST(WriteProducts, RejectsBadShapesAndNames) {
  TempDir dir;
  Texture t = shadow_map_texture();
  t.data.pop_back();
  EXPECT_THROW(write_products({t}, dir.path()), std::runtime_error);
  t = shadow_map_texture();
  t.name = "../escape";
  EXPECT_THROW(write_products({t}, dir.path()), std::runtime_error);
  // A file where the directory should be.
  const auto blocker = dir.write("blocker", "x");
  EXPECT_THROW(write_products({shadow_map_texture()}, blocker / "out"), std::runtime_error);
}

}  // namespace
}  // namespace shadow::output
