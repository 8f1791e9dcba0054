// EXR compression and the streaming writer: every offered compression reads back bit for bit
// (NaN, -0, denormals, 1.0 of empty texels), and a texture written row by row as its bytes
// arrive gives the same file contents as one written whole.
#include <cmath>
#include <cstring>
#include <limits>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include "output/exr_writer.hpp"
#include "output/stream_writer.hpp"
#include "output/write_products.hpp"
#include "temp_dir.hpp"

namespace shadow::output {
namespace {

using shadow::testing::TempDir;

// A shadow map's kind of content: smooth depths, empty texels at 1.0, and the awkward values.
Texture depth_texture(uint32_t w, uint32_t h) {
  Texture t;
  t.name = "shadowmap";
  t.kind = Product::kShadowMap;
  t.width = w;
  t.height = h;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      t.data.push_back(x + y < w / 2 ? 1.0f : 0.3f + 0.001f * std::sin(0.1f * x) * y);
  t.data[1] = std::numeric_limits<float>::quiet_NaN();
  t.data[2] = -0.0f;
  t.data[3] = std::numeric_limits<float>::denorm_min();
  t.data[4] = std::numeric_limits<float>::max();
  return t;
}

std::vector<float> read_floats(const std::filesystem::path& file, std::string* compression) {
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) throw std::runtime_error("cannot open " + file.string() + ": " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  if (compression) *compression = spec.get_string_attribute("compression");
  std::vector<float> out(spec.image_pixels() * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out.data()))
    throw std::runtime_error(in->geterror());
  return out;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(ExrCompression, EveryOfferedCompressionIsLossless) {
  TempDir dir;
  const Texture t = depth_texture(97, 61);
  for (std::string_view c : kExrCompressions) {
    const auto file = dir.path() / (std::string(c) + ".exr");
    write_exr(t, file, c);
    std::string stored;
    EXPECT_TRUE(same_bits(read_floats(file, &stored), t.data)) << c;
    EXPECT_EQ(stored, c == "auto" ? "none" : c);
  }
}

// "auto", the default: zip for visibility-valued products, none for depths and the rest; a
// named compression is written as named whatever the product.
TEST(ExrCompression, AutoIsZipForVisibilityAndNoneForTheRest) {
  TempDir dir;
  EXPECT_EQ(kDefaultExrCompression, "auto");
  EXPECT_TRUE(known_exr_compression(kDefaultExrCompression));
  EXPECT_FALSE(known_exr_compression("dwaa"));  // lossy
  Texture depth = depth_texture(64, 32);
  Texture visibility = depth_texture(64, 32);
  visibility.name = "visibility";
  visibility.kind = Product::kVisibility;
  Texture atlas = visibility;
  atlas.name = "shadow_atlas";
  atlas.kind = Product::kShadowAtlas;
  Texture position = depth_texture(32, 32);
  position.name = "position";
  position.kind = Product::kPosition;
  const std::vector<Texture> textures = {depth, visibility, atlas, position};
  const auto files = write_products(textures, dir.path());
  ASSERT_EQ(files.size(), 8u);  // each EXR and its PNG
  const char* expected[] = {"none", "zip", "zip", "none"};
  for (size_t i = 0; i < textures.size(); ++i) {
    std::string stored;
    EXPECT_TRUE(same_bits(read_floats(files.at(2 * i).path, &stored), textures[i].data));
    EXPECT_EQ(stored, expected[i]) << textures[i].name;
  }
  OutputOptions rle;
  rle.exr_compression = "rle";
  const auto named = write_products({visibility}, dir.path() / "rle", rle);
  std::string stored;
  read_floats(named.at(0).path, &stored);
  EXPECT_EQ(stored, "rle");
  EXPECT_THROW(write_exr(depth, dir.path() / "x.exr", "pxr24"), std::invalid_argument);
}

TEST(ExrCompression, NoPreviewWritesOnlyTheExr) {
  TempDir dir;
  OutputOptions o;
  o.preview = output::Preview::kNone;
  const auto files = write_products({depth_texture(16, 16)}, dir.path(), o);
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].path.extension(), ".exr");
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "shadowmap.png"));
}

// Bytes arrive in pieces that split rows and values; the files match the whole-texture path.
TEST(StreamWriter, RowsWrittenAsTheyArriveMatchTheWholeTexture) {
  TempDir dir;
  std::vector<Texture> textures = {depth_texture(113, 77), depth_texture(31, 9)};
  textures[1].name = "visibility";
  textures[1].kind = Product::kVisibility;
  Texture mip = depth_texture(8, 4);  // not plain: written by finish()
  mip.name = "shadowmap_mip0";
  mip.kind = Product::kShadowMapMips;
  textures.push_back(mip);

  std::vector<Texture> arriving = textures;  // the assembler's buffers: filled in as bytes come
  for (Texture& t : arriving) std::fill(t.data.begin(), t.data.end(), 0.0f);
  for (const std::string_view compression : {"none", "zips", "piz"}) {
    SCOPED_TRACE(compression);
    OutputOptions o;
    o.exr_compression = compression;
    StreamWriter writer(dir.path() / std::string(compression), o);
    writer.start(arriving);
    for (size_t i = 0; i < textures.size(); ++i) {
      const uint64_t size = textures[i].byte_size();
      for (uint64_t at = 0; at < size;) {
        const uint64_t n = std::min<uint64_t>(1001, size - at);  // splits floats and rows
        std::memcpy(reinterpret_cast<char*>(arriving[i].data.data()) + at,
                    reinterpret_cast<const char*>(textures[i].data.data()) + at, n);
        at += n;
        writer.arrived(i, at);
      }
    }
    const auto files = writer.finish(arriving);
    ASSERT_EQ(files.size(), 6u);  // three EXRs, three PNGs
    const auto at = dir.path() / std::string(compression);
    std::string stored;
    EXPECT_TRUE(same_bits(read_floats(at / "shadowmap.exr", &stored), textures[0].data));
    EXPECT_EQ(stored, compression);
    EXPECT_TRUE(same_bits(read_floats(at / "visibility.exr", nullptr), textures[1].data));
    EXPECT_TRUE(same_bits(read_floats(at / "shadowmap_mips.exr", nullptr), textures[2].data));
    for (const char* png : {"shadowmap.png", "visibility.png", "shadowmap_mips.png"})
      EXPECT_TRUE(std::filesystem::exists(at / png)) << png;
  }
}

TEST(StreamWriter, RefusesANameThatLeavesTheDirectory) {
  TempDir dir;
  Texture t = depth_texture(4, 4);
  t.name = "../escape";
  StreamWriter writer(dir.path(), {});
  EXPECT_THROW(writer.start({t}), std::runtime_error);
}

// Files written over are new files (a truncated one costs a flush on close, fresh_file.hpp): a
// hard link to the last render's file keeps its bytes, streamed or not. A symlink is written
// through, as before.
TEST(StreamWriter, WritesNewFilesOverOldOnes) {
  TempDir dir;
  Texture first = depth_texture(64, 16), second = depth_texture(64, 16);
  second.data[7] = 0.125f;
  Texture mip = depth_texture(8, 4);  // not plain: written whole by finish()
  mip.name = "shadowmap_mip0";
  mip.kind = Product::kShadowMapMips;
  const auto write = [&](const Texture& t) {
    StreamWriter writer(dir.path(), {});
    writer.start({t, mip});
    writer.arrived(0, t.byte_size());
    writer.arrived(1, mip.byte_size());
    return writer.finish({t, mip});
  };
  write(first);
  for (const char* name : {"shadowmap.exr", "shadowmap.png", "shadowmap_mips.exr"})
    std::filesystem::create_hard_link(dir.path() / name, dir.path() / (std::string("old_") + name));
  write(second);
  EXPECT_TRUE(same_bits(read_floats(dir.path() / "shadowmap.exr", nullptr), second.data));
  EXPECT_TRUE(same_bits(read_floats(dir.path() / "old_shadowmap.exr", nullptr), first.data));
  for (const char* name : {"shadowmap.exr", "shadowmap.png", "shadowmap_mips.exr"}) {
    const auto now = dir.path() / name, old = dir.path() / (std::string("old_") + name);
    EXPECT_EQ(std::filesystem::hard_link_count(now), 1u) << name;
    EXPECT_EQ(std::filesystem::hard_link_count(old), 1u) << name;
    EXPECT_GT(std::filesystem::file_size(old), 0u) << name;
  }

  const auto target = dir.path() / "elsewhere.exr";
  std::filesystem::rename(dir.path() / "shadowmap.exr", target);
  std::filesystem::create_symlink(target, dir.path() / "shadowmap.exr");
  write(first);
  EXPECT_TRUE(std::filesystem::is_symlink(dir.path() / "shadowmap.exr"));
  EXPECT_TRUE(same_bits(read_floats(target, nullptr), first.data));
}

}  // namespace
}  // namespace shadow::output
