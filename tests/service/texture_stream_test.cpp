// The Render stream: slicing a result into a header and bounded chunks, reassembling it, and
// rejecting every way a stream can break the protocol.
#include <cmath>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "stream_helpers.hpp"
#include "wire/result_assembler.hpp"
#include "wire/result_slicer.hpp"

namespace shadow::convert {
namespace {

Texture make_texture(const std::string& name, Product kind, uint32_t w, uint32_t h, uint32_t c) {
  Texture t;
  t.name = name;
  t.kind = kind;
  t.width = w;
  t.height = h;
  t.channels = c;
  t.world_to_ndc = glm::ortho(-1.0f, 2.0f, -3.0f, 4.0f, 0.5f, 9.0f);
  t.world_to_camera = glm::lookAt(glm::vec3(1, 2, 3), glm::vec3(0), glm::vec3(0, 1, 0));
  t.data.resize(size_t(w) * h * c);
  for (size_t i = 0; i < t.data.size(); ++i) t.data[i] = float(i) * 0.25f - 7.0f;
  t.data[3] = std::numeric_limits<float>::quiet_NaN();
  return t;
}

RenderResult make_result() {
  RenderResult r;
  r.textures.push_back(make_texture("position", Product::kPosition, 37, 23, 3));
  r.textures.push_back(make_texture("shadowmap", Product::kShadowMap, 8, 8, 1));
  r.passes = {"shadow_map.raster", "camera.raster", "shadow_test"};
  r.timings = {{"shadow_map.raster", 1.5}, {"shadow_test", 0.25}};
  return r;
}

TEST(TextureStream, RoundTripIsExactWithBoundedChunks) {
  const RenderResult in = make_result();
  const size_t chunk_bytes = 102;  // not a multiple of 4: chunks hold 25 whole floats
  const auto messages = stream(in, chunk_bytes);

  ASSERT_FALSE(messages.empty());
  ASSERT_TRUE(messages[0].has_header());
  const v1::RenderHeader& header = messages[0].header();
  ASSERT_EQ(header.textures_size(), 2);
  EXPECT_EQ(header.textures(0).byte_size(), 37u * 23 * 3 * 4);
  EXPECT_EQ(header.textures(0).kind(), v1::PRODUCT_POSITION);
  EXPECT_EQ(header.textures(0).format(), v1::PIXEL_FORMAT_FLOAT32);
  EXPECT_EQ(header.textures(1).faces(), 1u);
  size_t expected_chunks = 0;
  for (const Texture& t : in.textures) expected_chunks += (t.byte_size() + 99) / 100;
  EXPECT_EQ(messages.size(), 1 + expected_chunks);
  for (size_t i = 1; i < messages.size(); ++i) {
    ASSERT_TRUE(messages[i].has_chunk()) << i;
    EXPECT_LE(messages[i].chunk().data().size(), chunk_bytes);
    EXPECT_GT(messages[i].chunk().data().size(), 0u);
  }

  const RenderResult out = assemble(messages);
  ASSERT_EQ(out.textures.size(), in.textures.size());
  for (size_t i = 0; i < in.textures.size(); ++i) {
    const Texture& a = in.textures[i];
    const Texture& b = out.textures[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.channels, b.channels);
    EXPECT_EQ(a.faces, b.faces);
    EXPECT_EQ(a.world_to_ndc, b.world_to_ndc);
    EXPECT_EQ(a.world_to_camera, b.world_to_camera);
    ASSERT_EQ(a.data.size(), b.data.size());
    EXPECT_EQ(std::memcmp(a.data.data(), b.data.data(), a.byte_size()), 0) << a.name;
  }
  EXPECT_EQ(out.passes, in.passes);
  ASSERT_EQ(out.timings.size(), in.timings.size());
  EXPECT_EQ(out.timings[1].pass, "shadow_test");
  EXPECT_EQ(out.timings[1].device_ms, 0.25);
}

// Float16 textures: two bytes a value on the wire, whole values per chunk, bits kept; a header
// whose byte_size is not two bytes a value is refused.
TEST(TextureStream, Float16TravelsAtTwoBytesAValue) {
  RenderResult in;
  Texture t = make_texture("visibility", Product::kVisibility, 13, 7, 1);
  t.format = PixelFormat::kFloat16;
  t.data16.resize(t.data.size());
  for (size_t i = 0; i < t.data16.size(); ++i) t.data16[i] = uint16_t(0x3c00 + 37 * i);
  t.data16[5] = 0x7e01;  // a NaN with a payload
  t.data.clear();
  in.textures.push_back(t);
  const auto messages = stream(in, 33);  // 16 halves a chunk
  ASSERT_EQ(messages[0].header().textures(0).format(), v1::PIXEL_FORMAT_FLOAT16);
  EXPECT_EQ(messages[0].header().textures(0).byte_size(), 13u * 7 * 2);
  for (size_t i = 1; i < messages.size(); ++i) EXPECT_EQ(messages[i].chunk().data().size() % 2, 0u);
  const RenderResult out = assemble(messages);
  ASSERT_EQ(out.textures.size(), 1u);
  EXPECT_EQ(out.textures[0].format, PixelFormat::kFloat16);
  EXPECT_EQ(out.textures[0].data16, t.data16);
  EXPECT_TRUE(out.textures[0].data.empty());

  auto bad = messages;
  bad[0].mutable_header()->mutable_textures(0)->set_byte_size(13u * 7 * 4);
  EXPECT_THROW(assemble(bad), StreamError);
  // The slicer refuses a float16 texture that holds floats.
  in.textures[0].data.assign(t.data16.size(), 0.0f);
  EXPECT_THROW(stream(in, 33), std::logic_error);
}

TEST(TextureStream, EmptyResultIsJustAHeader) {
  const auto messages = stream(RenderResult{}, kDefaultChunkBytes);
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_TRUE(assemble(messages).textures.empty());
}

TEST(TextureStream, StopsWhenThePeerIsGone) {
  int writes = 0;
  EXPECT_FALSE(
      stream_result(make_result(), 64, [&](const v1::RenderResponse&) { return ++writes < 3; }));
  EXPECT_EQ(writes, 3);
}

TEST(TextureStream, RefusesATextureWhoseDataDoesNotMatchItsSize) {
  RenderResult r = make_result();
  r.textures[1].data.pop_back();
  EXPECT_THROW(stream_result(r, 64, [](const v1::RenderResponse&) { return true; }),
               std::logic_error);
}

// Each case breaks a good stream in one way; the assembler must refuse it.
struct Breakage {
  const char* name;
  std::function<void(std::vector<v1::RenderResponse>&)> apply;
};

class BrokenStream : public ::testing::TestWithParam<Breakage> {};

TEST_P(BrokenStream, IsRejected) {
  auto messages = stream(make_result(), 400);
  ASSERT_GE(messages.size(), 6u);
  GetParam().apply(messages);
  EXPECT_THROW(assemble(messages), StreamError);
}

v1::TextureInfo& texture_info(std::vector<v1::RenderResponse>& m, int i) {
  return *m[0].mutable_header()->mutable_textures(i);
}

INSTANTIATE_TEST_SUITE_P(
    Protocol, BrokenStream,
    ::testing::Values(
        Breakage{"chunk_before_header", [](auto& m) { std::swap(m[0], m[1]); }},
        Breakage{"second_header", [](auto& m) { m.insert(m.begin() + 2, m[0]); }},
        Breakage{"no_header", [](auto& m) { m.erase(m.begin()); }},
        Breakage{"empty_message", [](auto& m) { m[2].Clear(); }},
        Breakage{"gap", [](auto& m) { m.erase(m.begin() + 2); }},
        Breakage{"overlap", [](auto& m) { m.insert(m.begin() + 2, m[1]); }},
        Breakage{"missing_last_chunk", [](auto& m) { m.pop_back(); }},
        Breakage{"chunk_past_the_end",
                 [](auto& m) { m.back().mutable_chunk()->mutable_data()->append(4, '\0'); }},
        Breakage{"unknown_texture", [](auto& m) { m[1].mutable_chunk()->set_texture(7); }},
        Breakage{
            "byte_size_off_by_4",
            [](auto& m) { texture_info(m, 1).set_byte_size(texture_info(m, 1).byte_size() - 4); }},
        Breakage{"unsupported_format",
                 [](auto& m) { texture_info(m, 0).set_format(v1::PIXEL_FORMAT_UNSPECIFIED); }},
        Breakage{
            "bad_matrix",
            [](auto& m) { texture_info(m, 0).mutable_world_to_ndc()->mutable_m()->RemoveLast(); }},
        Breakage{"unspecified_kind",
                 [](auto& m) { texture_info(m, 1).set_kind(v1::PRODUCT_UNSPECIFIED); }},
        // Sizes whose product wraps 64 bits must be refused before anything is allocated.
        Breakage{"overflowing_size",
                 [](auto& m) {
                   auto& t = texture_info(m, 1);
                   t.set_width(0xffffffffu);
                   t.set_height(0xffffffffu);
                   t.set_channels(0xffffffffu);
                   t.set_byte_size(4);
                 }}),
    [](const auto& i) { return std::string(i.param.name); });

TEST(TextureStream, RefusesMoreBytesThanTheLimit) {
  const auto messages = stream(make_result(), 400);
  ResultAssembler assembler(/*max_total_bytes=*/1000);
  EXPECT_THROW(assembler.add(messages[0]), StreamError);
}

}  // namespace
}  // namespace shadow::convert
