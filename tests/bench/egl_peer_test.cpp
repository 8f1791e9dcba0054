// The raster bench's EGL peer draws what the engine's maps hold: NDC depth, row 0 at the top,
// nearer wins, empty texels at 1. Needs no display: EGL's device or surfaceless platform.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <vector>

#include "egl_peer.hpp"

namespace shadow::bench {
namespace {

// An axis-aligned quad given directly in texture NDC (world_to_ndc = identity).
void add_quad(std::vector<float>& positions, std::vector<uint32_t>& indices, float x0, float y0,
              float x1, float y1, float z) {
  const auto base = uint32_t(positions.size() / 3);
  for (const auto& [x, y] : {std::pair{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}})
    positions.insert(positions.end(), {x, y, z});
  indices.insert(indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

TEST(EglPeer, RendersAKnownDepth) {
  EglContext context;
  EXPECT_FALSE(context.description().empty());
  std::printf("EGL peer (%s platform): %s\n", context.platform().c_str(),
              context.description().c_str());
  constexpr uint32_t kSize = 8;
  DepthPeer peer(kSize);
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  // The near quad first, so that only the depth test keeps it in front of the far one.
  add_quad(positions, indices, 0.25f, 0.0f, 0.75f, 0.5f, 0.375f);  // texels x 2..5, rows 0..3
  add_quad(positions, indices, 0.0f, 0.25f, 0.5f, 1.0f, 0.75f);    // texels x 0..3, rows 2..7
  peer.upload(positions, indices);
  const DepthPeer::Timing t = peer.draw(glm::mat4(1.0f));
  EXPECT_GE(t.wall_ms, 0.0);
  EXPECT_GE(t.gpu_ms, 0.0);

  const std::vector<float> depth = peer.depth();
  ASSERT_EQ(depth.size(), size_t{kSize} * kSize);
  for (uint32_t y = 0; y < kSize; ++y) {
    for (uint32_t x = 0; x < kSize; ++x) {
      const bool near = x >= 2 && x <= 5 && y <= 3;
      const bool far = x <= 3 && y >= 2;
      const float want = near ? 0.375f : far ? 0.75f : 1.0f;
      // Exact under clip control (GL 4.5); within rounding through GL's -1..1 z otherwise.
      EXPECT_FLOAT_EQ(depth[y * kSize + x], want) << "texel " << x << ", " << y;
    }
  }
}

}  // namespace
}  // namespace shadow::bench
