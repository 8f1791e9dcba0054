// Shared by every program: matrix helpers and the records the host lays out in
// server/engine/device_types.hpp (keep the two in step; the host static_asserts the sizes).

// A 4x4 matrix travels as float16 in GLM's column-major order: s0123 is the first column.
inline float4 mul_m4(const float16 m, const float4 v) {
  return m.s0123 * v.x + m.s4567 * v.y + m.s89ab * v.z + m.scdef * v.w;
}

// One instance of a mesh in one pass (a shadow map or the camera view).
typedef struct {
  float16 to_clip;   // object -> this pass's clip space (world_to_ndc * transform)
  float16 to_world;  // object -> world
  uint vertex_base;  // first vertex of the mesh in the scene's position array
  uint index_base;   // first index of the mesh in the scene's index array
  uint vertex_count;
  uint triangle_count;
  uint out_vertex_base;    // first transformed vertex of this draw
  uint out_triangle_base;  // first primitive id of this draw
  uint instance;
  uint flags;  // DRAW_RECEIVES
  uint pad[8];
} draw_t;

#define DRAW_RECEIVES 1u

// Index of the last draw whose first vertex (by_triangle = 0) or first primitive
// (by_triangle = 1) is <= key; draws are sorted by both.
inline uint find_draw(global const draw_t* draws, uint count, uint key, int by_triangle) {
  uint lo = 0, hi = count;
  while (hi - lo > 1) {
    uint mid = (lo + hi) / 2;
    uint base = by_triangle ? draws[mid].out_triangle_base : draws[mid].out_vertex_base;
    if (base <= key)
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}
