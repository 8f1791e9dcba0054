// Host mirrors of the records kernels read (kernels/prelude.cl, raster.cl, scene.cl).
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

namespace shadow {

inline constexpr uint32_t kDrawReceives = 1u;
// Ping-pong blur: receiver class + 1 (0 = none) in bits 8..15 (DRAW_CLASS_SHIFT in prelude.cl).
inline constexpr uint32_t kDrawClassShift = 8;

// draw_t: one instance of a mesh in one pass.
struct alignas(64) DrawItem {
  glm::mat4 to_clip;
  glm::mat4 to_world;
  uint32_t vertex_base;
  uint32_t index_base;
  uint32_t vertex_count;
  uint32_t triangle_count;
  uint32_t out_vertex_base;
  uint32_t out_triangle_base;
  uint32_t instance;
  uint32_t flags;
  uint32_t pad[8];
};
static_assert(sizeof(DrawItem) == 192, "must match draw_t in kernels/prelude.cl");

// faces_t: which camera pixels one map of a cube decides (prelude.cl, owns_pixel).
struct alignas(64) FacesItem {
  glm::mat4 space;    // world -> the space in which the cube's faces are axis planes
  glm::vec4 origin;   // the projection centre in that space
  glm::vec4 inv_pos;  // per axis: 1 / distance from the centre to the + face, 0 if unused
  glm::vec4 inv_neg;  // per axis: 1 / distance to the - face, 0 if unused
  uint32_t owned;     // bit k: face k (+x -x +y -y +z -z); 0 = a single map, every pixel
  uint32_t pad[3];
};
static_assert(sizeof(FacesItem) == 128, "must match faces_t in kernels/prelude.cl");

// tri_t: a set-up triangle (raster.cl).
inline constexpr size_t kTriRecordBytes = 48;

// chunk_t: a slice of one mesh's vertices or indices (scene.cl).
struct ChunkItem {
  uint32_t first;
  uint32_t count;
  uint32_t limit;  // check_indices: the mesh's vertex count
  uint32_t mesh;   // host bookkeeping; the kernels ignore it
};

}  // namespace shadow
