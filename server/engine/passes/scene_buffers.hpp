// A scene on the device: every mesh's positions and indices in two scene-wide arrays, checked
// by kernels (non-finite positions, out-of-range indices) and measured (per-mesh bounds).
#pragma once

#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/runtime.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/light/light_space.hpp"
#include "wire/types.hpp"

namespace shadow {

struct MeshRange {
  uint32_t vertex_base = 0;
  uint32_t index_base = 0;
  uint32_t vertex_count = 0;
  uint32_t triangle_count = 0;
  Bounds bounds;  // object space
};

class SceneBuffers {
 public:
  // Uploads and checks the scene; throws InvalidArgument naming the first bad vertex or index.
  SceneBuffers(const cl::Runtime& runtime, cl::Kernels& kernels, const Scene& scene,
               Timeline& timeline);

  const cl::Buffer& positions() const { return positions_; }
  const cl::Buffer& indices() const { return indices_; }
  const std::vector<MeshRange>& meshes() const { return meshes_; }
  // Unique to this upload among the process' scenes: the step cache's keys name the scene by it.
  uint64_t id() const { return id_; }

 private:
  cl::Buffer positions_;
  cl::Buffer indices_;
  std::vector<MeshRange> meshes_;
  uint64_t id_;
};

}  // namespace shadow
