// End to end through the real server and client library: products, sizes, matrices, passes
// and timings, wire fidelity against the engine itself, and an 8192^2 map through the stream.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <future>

#include <glm/gtc/matrix_transform.hpp>

#include "server_fixture.hpp"
#include "test_scene.hpp"
#include "wire/convert.hpp"

namespace shadow::test {
namespace {

class RenderTest : public ServerFixture<> {};

const Texture& find(const RenderResult& r, Product kind) {
  auto it = std::find_if(r.textures.begin(), r.textures.end(),
                         [&](const Texture& t) { return t.kind == kind; });
  if (it == r.textures.end()) throw std::runtime_error("product missing");
  return *it;
}

glm::vec3 project(const glm::mat4& m, const glm::vec3& p) {
  const glm::vec4 h = m * glm::vec4(p, 1.0f);
  return glm::vec3(h) / h.w;
}

bool same_bits(const Texture& a, const Texture& b) {
  return a.data.size() == b.data.size() &&
         std::memcmp(a.data.data(), b.data.data(), a.byte_size()) == 0;
}

void expect_near(const glm::mat4& a, const glm::mat4& b, float tolerance) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(a[c][r], b[c][r], tolerance) << c << "," << r;
  }
}

TEST_F(RenderTest, SmallSceneReturnsEveryProductWithItsShapeAndMatrices) {
  const RenderRequest request = small_request();
  const RenderResult r = client().render(request);

  ASSERT_EQ(r.textures.size(), 3u);
  // In the order requested.
  EXPECT_EQ(r.textures[0].kind, Product::kShadowMap);
  EXPECT_EQ(r.textures[1].kind, Product::kVisibility);
  EXPECT_EQ(r.textures[2].kind, Product::kPosition);
  const Texture& map = find(r, Product::kShadowMap);
  const Texture& vis = find(r, Product::kVisibility);
  const Texture& pos = find(r, Product::kPosition);
  EXPECT_EQ(map.name, "shadowmap");
  EXPECT_EQ(vis.name, "visibility");
  EXPECT_EQ(pos.name, "position");
  for (const Texture* t : {&map, &vis, &pos}) {
    EXPECT_EQ(t->faces, 1u) << t->name;
    EXPECT_EQ(t->format, PixelFormat::kFloat32) << t->name;
    EXPECT_EQ(t->data.size(), size_t(t->width) * t->height * t->channels) << t->name;
  }
  EXPECT_EQ(map.width, 512u);
  EXPECT_EQ(map.height, 512u);
  EXPECT_EQ(map.channels, 1u);
  EXPECT_EQ(vis.width, 320u);
  EXPECT_EQ(vis.height, 240u);
  EXPECT_EQ(vis.channels, 1u);
  EXPECT_EQ(pos.width, 320u);
  EXPECT_EQ(pos.height, 240u);
  EXPECT_EQ(pos.channels, 3u);

  // Passes ran, and every timing belongs to one of them.
  EXPECT_FALSE(r.passes.empty());
  EXPECT_FALSE(r.timings.empty());
  for (const PassTiming& t : r.timings) {
    EXPECT_NE(std::find(r.passes.begin(), r.passes.end(), t.pass), r.passes.end()) << t.pass;
    EXPECT_TRUE(std::isfinite(t.device_ms) && t.device_ms >= 0.0) << t.pass;
  }

  // The per-pixel products look through the camera.
  const Camera& cam = request.camera;
  expect_near(vis.world_to_camera, glm::lookAt(cam.eye, cam.target, cam.up), 1e-5f);
  expect_near(pos.world_to_ndc, vis.world_to_ndc, 0.0f);

  // Depth values are NDC z in [0, 1] and the map is not constant.
  const auto [lo, hi] = std::minmax_element(map.data.begin(), map.data.end());
  EXPECT_GE(*lo, 0.0f);
  EXPECT_LE(*hi, 1.0f);
  EXPECT_LT(*lo, *hi);
  EXPECT_TRUE(std::all_of(map.data.begin(), map.data.end(), [](float d) { return d == d; }));

  // Per pixel: sky is NaN in both products; a seen point projects back to its own pixel
  // centre through world_to_ndc, and whether it is lit agrees with the shadow map's depth.
  const uint32_t W = vis.width, H = vis.height, S = map.width;
  size_t sky = 0, lit = 0, shadowed = 0, lit_agree = 0, shadowed_agree = 0, off_pixel = 0;
  for (uint32_t j = 0; j < H; ++j) {
    for (uint32_t i = 0; i < W; ++i) {
      const size_t k = size_t(j) * W + i;
      const float v = vis.data[k];
      const glm::vec3 p(pos.data[3 * k], pos.data[3 * k + 1], pos.data[3 * k + 2]);
      if (std::isnan(v)) {
        EXPECT_TRUE(std::isnan(p.x)) << i << "," << j;
        ++sky;
        continue;
      }
      ASSERT_TRUE(v >= 0.0f && v <= 1.0f) << v;
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
      EXPECT_TRUE(std::abs(p.x) <= 10.01f && p.y >= -0.01f && p.y <= 2.01f &&
                  std::abs(p.z) <= 10.01f)
          << p.x << "," << p.y << "," << p.z;
      const glm::vec3 c = project(vis.world_to_ndc, p);
      if (std::abs(c.x * W - (i + 0.5f)) > 0.25f || std::abs(c.y * H - (j + 0.5f)) > 0.25f) {
        ++off_pixel;
      }
      const glm::vec3 s = project(map.world_to_ndc, p);
      const int u = std::clamp(int(s.x * S), 0, int(S) - 1);
      const int w = std::clamp(int(s.y * S), 0, int(S) - 1);
      const float depth = map.data[size_t(w) * S + u];
      if (v > 0.5f) {
        ++lit;
        lit_agree += depth >= s.z - 0.02f;
      } else {
        ++shadowed;
        shadowed_agree += depth < s.z;
      }
    }
  }
  EXPECT_GT(sky, 0u) << "the top rows look above the horizon";
  EXPECT_GT(lit, 0u);
  EXPECT_GT(shadowed, 0u) << "the box casts a shadow in view";
  EXPECT_EQ(off_pixel, 0u);
  EXPECT_GE(lit_agree, lit * 95 / 100);
  EXPECT_GE(shadowed_agree, shadowed * 95 / 100);
}

TEST_F(RenderTest, TexturesThroughTheWireEqualTheEnginesOwn) {
  const RenderRequest request = small_request();
  const RenderResult wire = client().render(request);
  const RenderResult direct = server().engine().render(request);
  ASSERT_EQ(wire.textures.size(), direct.textures.size());
  for (size_t i = 0; i < wire.textures.size(); ++i) {
    const Texture& a = wire.textures[i];
    const Texture& b = direct.textures[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.channels, b.channels);
    EXPECT_EQ(a.world_to_ndc, b.world_to_ndc);
    EXPECT_EQ(a.world_to_camera, b.world_to_camera);
    EXPECT_TRUE(same_bits(a, b)) << a.name;
  }
  EXPECT_EQ(wire.passes, direct.passes);
}

// zstd-compressed chunks (the server's compressor, the client's decompressor) change no bit.
TEST_F(RenderTest, ZstdCompressedRepliesEqualTheEnginesOwn) {
  const RenderRequest request = small_request();
  v1::RenderRequest proto = convert::to_proto(request);
  proto.set_chunk_compression(v1::CHUNK_COMPRESSION_ZSTD);
  const RenderResult wire = client().render(proto);
  const RenderResult direct = server().engine().render(request);
  ASSERT_EQ(wire.textures.size(), direct.textures.size());
  for (size_t i = 0; i < wire.textures.size(); ++i)
    EXPECT_TRUE(same_bits(wire.textures[i], direct.textures[i])) << wire.textures[i].name;
}

TEST_F(RenderTest, ShadowMap8192ComesBackIntactThroughTheChunkedStream) {
  RenderRequest request = small_request({Product::kShadowMap});
  request.shadow_map.size = 8192;
  request.camera.width = 64;
  request.camera.height = 48;
  const RenderResult r = client().render(request);

  ASSERT_EQ(r.textures.size(), 1u);
  const Texture& map = r.textures[0];
  EXPECT_EQ(map.width, 8192u);
  EXPECT_EQ(map.height, 8192u);
  EXPECT_EQ(map.channels, 1u);
  ASSERT_EQ(map.byte_size(), size_t{256} << 20);
  float lo = 1.0f, hi = 0.0f;
  size_t outside = 0;
  for (float d : map.data) {
    if (!(d >= 0.0f && d <= 1.0f)) ++outside;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  EXPECT_EQ(outside, 0u);
  EXPECT_LT(lo, hi);
  // The box's top, above the origin, is in the map.
  const glm::vec3 top = project(map.world_to_ndc, {0.0f, 2.0f, 0.0f});
  EXPECT_TRUE(top.x > 0 && top.x < 1 && top.y > 0 && top.y < 1 && top.z >= 0 && top.z <= 1);

  // Every byte survived: the same map straight from the engine.
  const RenderResult direct = server().engine().render(request);
  ASSERT_EQ(direct.textures.size(), 1u);
  EXPECT_TRUE(same_bits(map, direct.textures[0]));
}

TEST_F(RenderTest, ConcurrentRequestsAllSucceed) {
  const v1::RenderRequest request = tiny_proto_request();
  std::vector<std::future<RenderResult>> calls;
  for (int i = 0; i < 4; ++i) {
    calls.push_back(std::async(std::launch::async, [&] { return client().render(request); }));
  }
  std::vector<RenderResult> results;
  for (auto& call : calls) results.push_back(call.get());
  for (const RenderResult& r : results) {
    ASSERT_EQ(r.textures.size(), results[0].textures.size());
    for (size_t i = 0; i < r.textures.size(); ++i) {
      EXPECT_TRUE(same_bits(r.textures[i], results[0].textures[i])) << r.textures[i].name;
    }
  }
}

}  // namespace
}  // namespace shadow::test
