// Mesa's llvmpipe through OSMesa as a peer for the rasterizer bench: depth only, the same
// world->texture-NDC matrix, indexed triangles in one vertex buffer uploaded once.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

namespace shadow::bench {

class LlvmpipePeer {
 public:
  // Sets LP_NUM_THREADS (if unset) to `threads` before Mesa starts; throws if OSMesa fails.
  LlvmpipePeer(uint32_t size, int threads);
  ~LlvmpipePeer();
  LlvmpipePeer(const LlvmpipePeer&) = delete;
  LlvmpipePeer& operator=(const LlvmpipePeer&) = delete;

  // World-space positions (xyz) and triangle indices; replaces the previous mesh.
  void upload(const std::vector<float>& positions, const std::vector<uint32_t>& indices);
  // Clears depth to 1 and draws every triangle through `world_to_ndc` (x, y 0..1 from the
  // top-left, z 0..1, this project's convention); returns the wall time in ms (glFinish).
  double draw(const glm::mat4& world_to_ndc);
  // The depth of texel (x, y), row 0 at the top as in the project's maps, z in 0..1.
  std::vector<float> depth() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadow::bench
