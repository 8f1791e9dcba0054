// zstd-compressed Render streams (RenderRequest.chunk_compression): the assembled textures are
// bit-identical to an uncompressed stream's, and a lying compressed chunk (wrong sizes, not a
// frame, trailing bytes, a frame that decompresses past what it declares) is a StreamError.
#include <bit>
#include <cstring>
#include <limits>
#include <random>

#include <zstd.h>

#include <gtest/gtest.h>

#include "stream_helpers.hpp"
#include "wire/result_assembler.hpp"
#include "wire/result_slicer.hpp"

namespace shadow::convert {
namespace {

// An empty region (1.0, compresses to nothing), smooth depths, NaN holes, and a noisy band that
// does not shrink: both kinds of chunk appear in one stream.
Texture map_texture(uint32_t w, uint32_t h) {
  Texture t;
  t.name = "shadowmap";
  t.kind = Product::kShadowMap;
  t.width = w;
  t.height = h;
  std::mt19937 rng(7);  // random bits: incompressible (some are NaN payloads; bits are compared)
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      t.data.push_back(y < h / 3       ? 1.0f
                       : y < 2 * h / 3 ? 0.25f + 1e-4f * x + 1e-3f * y
                                       : std::bit_cast<float>(uint32_t(rng())));
  t.data[w * h / 2] = std::numeric_limits<float>::quiet_NaN();
  return t;
}

RenderResult make_result() {
  RenderResult r;
  r.textures.push_back(map_texture(256, 96));
  Texture sat;
  sat.name = "shadowmap_sat";
  sat.kind = Product::kShadowMapSat;
  sat.format = PixelFormat::kFloat64;
  sat.width = 40;
  sat.height = 30;
  for (int i = 0; i < 40 * 30; ++i) sat.data64.push_back(i * 0.125);
  r.textures.push_back(sat);
  return r;
}

std::vector<v1::RenderResponse> zstd_stream(const RenderResult& r, size_t chunk_bytes) {
  std::vector<v1::RenderResponse> out;
  EXPECT_TRUE(stream_result(
      r, chunk_bytes,
      [&](const v1::RenderResponse& m) {
        out.emplace_back();
        EXPECT_TRUE(out.back().ParseFromString(m.SerializeAsString()));
        return true;
      },
      ChunkCompression::kZstd));
  return out;
}

TEST(CompressedStream, AssemblesToTheSameBitsAsUncompressed) {
  const RenderResult in = make_result();
  const size_t chunk_bytes = 4096;
  const auto raw = stream(in, chunk_bytes);
  const auto packed = zstd_stream(in, chunk_bytes);
  ASSERT_EQ(raw.size(), packed.size());  // the same chunks, some of them compressed
  size_t raw_bytes = 0, packed_bytes = 0, compressed = 0, sent_raw = 0;
  for (size_t i = 1; i < packed.size(); ++i) {
    const v1::TextureChunk& c = packed[i].chunk();
    EXPECT_EQ(c.offset(), raw[i].chunk().offset());
    raw_bytes += raw[i].chunk().data().size();
    packed_bytes += c.data().size();
    if (c.compression() == v1::CHUNK_COMPRESSION_ZSTD) {
      ++compressed;
      EXPECT_EQ(c.raw_size(), raw[i].chunk().data().size());
      EXPECT_LT(c.data().size(), c.raw_size());
    } else {
      ++sent_raw;
      EXPECT_EQ(c.compression(), v1::CHUNK_COMPRESSION_NONE);
      EXPECT_EQ(c.data(), raw[i].chunk().data());
    }
  }
  EXPECT_GT(compressed, 0u);
  EXPECT_GT(sent_raw, 0u);  // the noise does not shrink and goes raw
  EXPECT_LT(packed_bytes, raw_bytes * 3 / 4);

  const RenderResult a = assemble(raw), b = assemble(packed);
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (size_t i = 0; i < a.textures.size(); ++i) {
    const Texture &x = in.textures[i], &y = b.textures[i];
    ASSERT_EQ(x.byte_size(), y.byte_size());
    const void* px = x.data.empty() ? (const void*)x.data64.data() : x.data.data();
    const void* py = y.data.empty() ? (const void*)y.data64.data() : y.data.data();
    EXPECT_EQ(std::memcmp(px, py, x.byte_size()), 0) << x.name;
    const void* pa = a.textures[i].data.empty() ? (const void*)a.textures[i].data64.data()
                                                : a.textures[i].data.data();
    EXPECT_EQ(std::memcmp(pa, py, x.byte_size()), 0) << x.name;
  }
}

// zstd of `bytes` as one frame with its content size.
std::string frame_of(const std::string& bytes) {
  std::string out(ZSTD_compressBound(bytes.size()), '\0');
  const size_t n = ZSTD_compress(out.data(), out.size(), bytes.data(), bytes.size(), 1);
  EXPECT_FALSE(ZSTD_isError(n));
  out.resize(n);
  return out;
}

// The first chunk of texture 0 (message 1), compressed; `lie` then breaks it.
void break_first_chunk(std::vector<v1::RenderResponse>& m,
                       const std::function<void(v1::TextureChunk&)>& lie) {
  v1::TextureChunk& c = *m[1].mutable_chunk();
  ASSERT_EQ(c.compression(), v1::CHUNK_COMPRESSION_ZSTD);
  lie(c);
}

struct Lie {
  const char* name;
  std::function<void(v1::TextureChunk&)> apply;
  const char* message;  // part of the StreamError's text
};

class LyingChunk : public ::testing::TestWithParam<Lie> {};

TEST_P(LyingChunk, IsAStreamError) {
  auto messages = zstd_stream(make_result(), 4096);
  break_first_chunk(messages, GetParam().apply);
  try {
    assemble(messages);
    FAIL() << "assembled";
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find(GetParam().message), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Hostile, LyingChunk,
    ::testing::Values(
        Lie{"raw_size_too_small", [](auto& c) { c.set_raw_size(c.raw_size() - 4); },
            "declares 4096 bytes, but raw_size 4092"},
        Lie{"raw_size_too_large", [](auto& c) { c.set_raw_size(c.raw_size() + 4); },
            "declares 4096 bytes, but raw_size 4100"},
        Lie{"raw_size_past_the_texture", [](auto& c) { c.set_raw_size(uint64_t{1} << 40); },
            "past its size"},
        Lie{"raw_size_on_a_raw_chunk",
            [](auto& c) {
              c.set_compression(v1::CHUNK_COMPRESSION_NONE);
              c.set_data(std::string(4096, '\0'));
            },
            "an uncompressed chunk of textures[0] (shadowmap) has raw_size 4096"},
        Lie{"unknown_compression", [](auto& c) { c.set_compression(v1::ChunkCompression(9)); },
            "unknown compression 9"},
        Lie{"garbage", [](auto& c) { c.set_data("this is not zstd at all"); },
            "is not a zstd frame"},
        Lie{"empty", [](auto& c) { c.clear_data(); }, "is not a zstd frame"},
        Lie{"truncated_frame", [](auto& c) { c.mutable_data()->resize(c.data().size() - 3); },
            "is not one whole zstd frame"},
        Lie{"trailing_bytes", [](auto& c) { c.mutable_data()->append(frame_of("x")); },
            "is not one whole zstd frame"},
        Lie{"no_declared_size",
            [](auto& c) {
              // A streamed frame: ZSTD_compressStream2 without a pledged size omits it.
              ZSTD_CCtx* z = ZSTD_createCCtx();
              std::string in(4096, 'a'), out(ZSTD_compressBound(4096) + 64, '\0');
              ZSTD_inBuffer ib{in.data(), 0, 0};  // nothing yet: size unknown at the start
              ZSTD_outBuffer ob{out.data(), out.size(), 0};
              ZSTD_compressStream2(z, &ob, &ib, ZSTD_e_continue);
              ib = {in.data(), in.size(), 0};
              while (ZSTD_compressStream2(z, &ob, &ib, ZSTD_e_end) != 0) {
              }
              ZSTD_freeCCtx(z);
              out.resize(ob.pos);
              c.set_data(out);
            },
            "does not declare its size"},
        // A bomb: 64 MiB of zeros in a few KiB, declared as 4096 bytes. The decompressor may
        // write only the 4096 bytes the chunk has room for.
        Lie{"decompression_bomb",
            [](auto& c) {
              std::string bomb = frame_of(std::string(64 << 20, '\0'));
              // Frame header: magic (4), descriptor (1), window byte unless single-segment,
              // then the content size; rewrite a 4-byte size to claim 4096.
              const uint8_t d = uint8_t(bomb[4]);
              ASSERT_EQ(d >> 6, 2) << "expected a 4-byte content size";
              const size_t at = 5 + ((d >> 5) & 1 ? 0 : 1);
              const uint32_t claim = 4096;
              std::memcpy(bomb.data() + at, &claim, 4);  // little-endian host
              c.set_data(bomb);
            },
            "does not decompress to its 4096 bytes"}),
    [](const auto& i) { return std::string(i.param.name); });

}  // namespace
}  // namespace shadow::convert
