// Cube shadow maps as one multi-subimage EXR: a subimage per rendered face, named after it,
// with its own matrices (p · M convention) and textureformat "CubeFace Shadow"; the PNG stacks
// the faces; a cube with no rendered face writes nothing.
#include <array>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "exr_matrix.hpp"
#include "output/cube_writer.hpp"
#include "output/write_products.hpp"
#include "temp_dir.hpp"

namespace shadow::output {
namespace {

using shadow::testing::matrix;
using shadow::testing::row_times;
using shadow::testing::TempDir;

// A point light's face: 90-degree perspective looking along `axis`, into 0..1 texture space.
TextureFace face(const std::string& name, glm::vec3 axis, glm::vec3 up) {
  const glm::vec3 light(1, 4, -2);
  TextureFace f;
  f.name = name;
  f.world_to_camera = glm::lookAt(light, light + axis, up);
  const glm::mat4 ndc_to_uv = glm::translate(glm::mat4(1.0f), glm::vec3(0.5f, 0.5f, 0)) *
                              glm::scale(glm::mat4(1.0f), glm::vec3(0.5f, -0.5f, 1));
  f.world_to_ndc =
      ndc_to_uv * glm::perspective(glm::radians(90.0f), 1.0f, 0.1f, 50.0f) * f.world_to_camera;
  return f;
}

Texture three_face_cube() {
  Texture t;
  t.name = "shadowmap_cube";
  t.kind = Product::kShadowMap;
  t.width = 4;
  t.height = 4;
  t.cube_faces = {face("+x", {1, 0, 0}, {0, -1, 0}), face("-y", {0, -1, 0}, {0, 0, -1}),
                  face("+z", {0, 0, 1}, {0, -1, 0})};
  t.faces = 3;
  for (uint32_t i = 0; i < 3 * 16; ++i) t.data.push_back(0.25f + float(i) / 128.0f);
  return t;
}

void expect_near(glm::vec4 a, glm::vec4 b, const std::string& what) {
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(a[i], b[i], 1e-4f * (1 + std::abs(b[i]))) << what << i;
}

TEST(CubeOutput, OneExrWithASubimagePerFace) {
  TempDir dir;
  const Texture t = three_face_cube();
  const auto written = write_products({t}, dir.path());
  ASSERT_EQ(written.size(), 2u);
  EXPECT_EQ(written[0].path.filename(), "shadowmap_cube.exr");
  EXPECT_EQ(written[1].path.filename(), "shadowmap_cube.png");

  auto in = OIIO::ImageInput::open(written[0].path.string());
  ASSERT_TRUE(in) << OIIO::geterror();
  const glm::vec4 p(2.5f, 3.0f, 1.0f, 1.0f);  // in front of +x
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(in->seek_subimage(i, 0)) << i;
    const OIIO::ImageSpec& spec = in->spec();
    const TextureFace& f = t.cube_faces[i];
    EXPECT_EQ(spec.get_string_attribute("oiio:subimagename"), f.name) << i;
    EXPECT_EQ(spec.get_string_attribute("textureformat"), "CubeFace Shadow") << i;
    EXPECT_EQ(spec.width, 4);
    EXPECT_EQ(spec.height, 4);
    ASSERT_EQ(spec.nchannels, 1);
    EXPECT_EQ(spec.channelnames[0], "Z");
    expect_near(row_times(p, matrix(spec, "worldtoNDC")), f.world_to_ndc * p, f.name + " ndc ");
    expect_near(row_times(p, matrix(spec, "worldtocamera")), f.world_to_camera * p,
                f.name + " camera ");
    std::vector<float> px(16);
    ASSERT_TRUE(in->read_image(i, 0, 0, 1, OIIO::TypeDesc::FLOAT, px.data()));
    EXPECT_EQ(px, std::vector<float>(t.data.begin() + 16 * i, t.data.begin() + 16 * (i + 1)));
  }
  EXPECT_FALSE(in->seek_subimage(3, 0));
  in.reset();

  // The faces' matrices differ, so a face with another's matrix would have failed above.
  EXPECT_NE(t.cube_faces[0].world_to_ndc, t.cube_faces[1].world_to_ndc);

  auto png = OIIO::ImageInput::open(written[1].path.string());
  ASSERT_TRUE(png);
  EXPECT_EQ(png->spec().width, 4);
  EXPECT_EQ(png->spec().height, 12);  // the faces stacked
}

TEST(CubeOutput, NoRenderedFaceWritesNoFile) {
  TempDir dir;
  Texture t = three_face_cube();
  t.cube_faces.clear();
  t.faces = 0;
  t.data.clear();
  EXPECT_TRUE(is_cube(t));
  EXPECT_TRUE(write_products({t}, dir.path()).empty());
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
  EXPECT_THROW(write_cube_exr(t, dir.path() / "c.exr"), std::runtime_error);
}

TEST(CubeOutput, RefusesFacesThatDoNotMatchTheData) {
  TempDir dir;
  Texture t = three_face_cube();
  t.cube_faces.pop_back();
  EXPECT_THROW(write_cube_exr(t, dir.path() / "c.exr"), std::runtime_error);
  t = three_face_cube();
  t.data.pop_back();
  EXPECT_THROW(write_cube_exr(t, dir.path() / "c.exr"), std::runtime_error);
}

TEST(CubeOutput, PlainTexturesAreNotCubes) {
  Texture t;
  EXPECT_FALSE(is_cube(t));
  t.cube_faces.push_back({});
  EXPECT_TRUE(is_cube(t));
}

}  // namespace
}  // namespace shadow::output
