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
  uint flags;  // DRAW_RECEIVES | (receiver class + 1) << DRAW_CLASS_SHIFT
  uint pad[8];
} draw_t;

#define DRAW_RECEIVES 1u
#define DRAW_CLASS_SHIFT 8  // ping-pong blur class + 1 (0 = none) in bits 8..15

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

// Slope bias stays finite where the receiver is edge-on to the light.
#define MAX_SLOPE 1.0f

// The receiver plane's NDC-depth change per shadow-map texel (dz/du, dz/dv) from the point's
// normal and clip position c through the light's world_to_ndc (exact for planes, any matrix);
// infinite where the plane is edge-on. Shared by the shadow test and the filters (pcf.cl).
inline float2 depth_gradient(float16 m, float3 n, float4 c, float map_size) {
  float3 t1 = fabs(n.x) < 0.9f ? cross(n, (float3)(1, 0, 0)) : cross(n, (float3)(0, 1, 0));
  t1 = normalize(t1);
  float3 t2 = cross(n, t1);
  float4 m1 = mul_m4(m, (float4)(t1, 0.0f)), m2 = mul_m4(m, (float4)(t2, 0.0f));
  float3 ndc = c.xyz / c.w;
  float3 d1 = (m1.xyz - ndc * m1.w) / c.w, d2 = (m2.xyz - ndc * m2.w) / c.w;
  float det = d1.x * d2.y - d2.x * d1.y;
  if (det == 0.0f) return (float2)(INFINITY);
  float gx = (d1.z * d2.y - d2.z * d1.y) / det, gy = (d1.x * d2.z - d2.x * d1.z) / det;
  return (float2)(gx, gy) / map_size;
}
inline float depth_slope(float16 m, float3 p, float3 n, float4 c, float map_size) {
  float2 g = depth_gradient(m, n, c, map_size);
  return fmin(fabs(g.x) + fabs(g.y), MAX_SLOPE);
}

// Light kinds as the host passes them to the per-pixel kernels.
#define LIGHT_DIRECTIONAL 0
#define LIGHT_SPOT 1
#define LIGHT_POINT 2

// The cube face of direction (dx, dy, dz): 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z by the major axis,
// ties to x, then y (as engine/cube_fit.cpp). NaN goes to +z. Selects only, so it vectorizes.
inline uint cube_face(float dx, float dy, float dz) {
  float ax = fabs(dx), ay = fabs(dy), az = fabs(dz);
  int x_major = (ax >= ay) & (ax >= az), y_major = !x_major & (ay >= az);
  float d = x_major ? dx : y_major ? dy : dz;
  return (x_major ? 0u : y_major ? 2u : 4u) + (d < 0.0f ? 1u : 0u);
}

// Whether a launch for the map owning `owned_faces` (bit k = cube face k, 0 = a single map that
// owns every pixel) decides the pixel at (x, y, z); other launches decide the rest.
inline int owns_pixel(uint owned_faces, float x, float y, float z, float4 light_position) {
  uint face = cube_face(x - light_position.x, y - light_position.y, z - light_position.z);
  return (owned_faces == 0u) | ((owned_faces >> face) & 1u);
}

// Outside a spot light's cone nothing is lit, receiver or not.
inline bool outside_spot_cone(float3 x, int light_kind, float4 light_position, float4 light_axis,
                              float cos_half_cone) {
  return light_kind == LIGHT_SPOT &&
         dot(normalize(x - light_position.xyz), light_axis.xyz) < cos_half_cone;
}
