// Generated UV layouts (xatlas) for receiving meshes that have no UVs, when a request wants the
// shadow atlas. Host work at set-up, bounded by kMaxLayoutTriangles a mesh and made once: the
// layouts are kept by mesh content (the frames of a sequence that move instances copy the
// scene, not its meshes' contents) and by scene (an uploaded scene's requests share one
// laid-out scene, so its device copy stays resident).
#pragma once

#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <vector>

#include "wire/types.hpp"

namespace shadow {

// Meshes with more triangles than this are refused a generated layout (give them UVs): xatlas
// grows faster than linearly, 0.6 s for 9 800 triangles and 21 s for 99 500 (2-core AMD EPYC).
constexpr uint64_t kMaxLayoutTriangles = 20000;
// Its cost for the admission estimate, per triangle (the measured 9 800-triangle rate, doubled).
constexpr double kLayoutNsPerTriangle = 120e3;
// Coordinates a layout is generated for, at most, in magnitude, so that their squares stay
// finite in float: xatlas did not return for a box with one vertex at 1e20 (fine at 1e19).
constexpr float kMaxLayoutCoordinate = 1e18f;

// `mesh` re-indexed with xatlas' vertices (positions and normals copied from the vertex each
// came from, triangles in their order) and UVs in [0, 1]: charts apart, without overlaps.
Mesh generate_uv_layout(const Mesh& mesh);

// The meshes a layout is generated for: those that some instance receives on and that have no
// UVs (or all of them: `all`, AtlasSettings::generate_uvs), in increasing order.
std::vector<uint32_t> meshes_to_lay_out(const Scene& scene, bool all);

class UvLayouts {
 public:
  // `scene` with the meshes of meshes_to_lay_out(*scene, all) laid out, or `scene` itself when
  // there are none. Thread-safe.
  std::shared_ptr<const Scene> apply(const std::shared_ptr<const Scene>& scene, bool all);

 private:
  struct ByMesh {
    Mesh source;  // positions, indices and normals: the key, compared whole
    std::shared_ptr<const Mesh> laid_out;
  };
  struct ByScene {
    std::weak_ptr<const Scene> source;
    bool all;
    std::shared_ptr<const Scene> laid_out;
  };
  std::shared_ptr<const Mesh> layout_of(const Mesh& mesh);  // under mutex_

  static constexpr size_t kMeshes = 32, kScenes = 16;  // most recently used first
  std::mutex mutex_;
  std::list<ByMesh> meshes_;
  std::list<ByScene> scenes_;
};

}  // namespace shadow
