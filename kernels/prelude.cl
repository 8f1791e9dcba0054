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

// The world-space corners of primitive `prim` (numbered as the draws number their triangles)
// of draw `d`.
inline void world_triangle(global const float* positions, global const uint* indices,
                           global const draw_t* d, uint prim, float3* a, float3* b, float3* c) {
  global const uint* idx = indices + d->index_base + 3 * (prim - d->out_triangle_base);
  float16 m = d->to_world;
  uint vb = d->vertex_base;
  *a = mul_m4(m, (float4)(vload3(vb + idx[0], positions), 1.0f)).xyz;
  *b = mul_m4(m, (float4)(vload3(vb + idx[1], positions), 1.0f)).xyz;
  *c = mul_m4(m, (float4)(vload3(vb + idx[2], positions), 1.0f)).xyz;
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

// Light kinds (light_t.kind), for the per-pixel kernels and the rasterizer's world-space bias.
#define LIGHT_DIRECTIONAL 0
#define LIGHT_SPOT 1
#define LIGHT_POINT 2

// The light, as every kernel that needs it takes it (device_types.hpp: LightItem).
typedef struct {
  float4 position;      // spot: apex; point: the light; w = 1 (directional: unused)
  float4 axis;          // unit direction of travel (directional) or cone axis (spot); w = 0
  float cos_half_cone;  // spot: outside the cone nothing is lit
  int kind;             // LIGHT_DIRECTIONAL, LIGHT_SPOT or LIGHT_POINT
  float disk;           // the area light's disk: tan(angular radius) for a sun, else its radius
  uint pad;
} light_t;

// One shadow-map lookup: what every per-pixel kernel (shadow_test, pcf, pcss, blur_visibility)
// needs to take a camera point into the map and compare it there (device_types.hpp:
// ShadowLookupItem). The map itself is a buffer argument beside it.
typedef struct {
  float16 to_ndc;       // world -> the map's texture NDC (x, y in [0, 1], z the depth)
  light_t light;        // offset 64
  uint map_size;        // texels per side (offset 112)
  float bias_constant;  // NDC-depth bias: constant
  float bias_slope;     //   plus this times the receiver's depth slope per texel
  uint pad;
} shadow_lookup_t;

// Which camera pixels one map of a cube decides (engine/light_space.hpp, CubeFaces): the face
// through which the line from `origin` through the point leaves the cube in `space`, i.e. the
// largest ratio d_i * inv_pos_i, -d_i * inv_neg_i (Kozlov, listing 14-1), ties to the earlier
// face in +x -x +y -y +z -z order. owned = 0: a single map that decides every pixel.
typedef struct {
  float16 space;
  float4 origin, inv_pos, inv_neg;
  uint owned;
  uint pad[3];
} faces_t;

// The face (0..5) whose map decides world point (x, y, z). Selects only, so it vectorizes.
inline uint cube_face(const faces_t* f, float x, float y, float z) {
  float16 m = f->space;
  // d = p' - origin times p's w: the ratios only get compared, and every camera pixel lies in
  // front of the space's camera (w > 0), so no division.
  float hw = m.s3 * x + m.s7 * y + m.sb * z + m.sf;
  float dx = m.s0 * x + m.s4 * y + m.s8 * z + m.sc - hw * f->origin.x;
  float dy = m.s1 * x + m.s5 * y + m.s9 * z + m.sd - hw * f->origin.y;
  float dz = m.s2 * x + m.s6 * y + m.sa * z + m.se - hw * f->origin.z;
  // The running maximum, unrolled: a private array indexed in a loop stops LLVM vectorizing
  // the pixel loops that call this.
  uint face = 0;
  float most = dx * f->inv_pos.x, r = -dx * f->inv_neg.x;
  face = r > most ? 1u : face, most = fmax(most, r);
  r = dy * f->inv_pos.y;
  face = r > most ? 2u : face, most = fmax(most, r);
  r = -dy * f->inv_neg.y;
  face = r > most ? 3u : face, most = fmax(most, r);
  r = dz * f->inv_pos.z;
  face = r > most ? 4u : face, most = fmax(most, r);
  r = -dz * f->inv_neg.z;
  return r > most ? 5u : face;
}

// For the kernels that run once per face (CSM's lookups). Compiled in only for cube faces
// (-DCUBE_FACES): a single map owns every pixel and pays nothing.
inline int owns_pixel(const faces_t* f, float x, float y, float z) {
#ifndef CUBE_FACES
  return 1;
#endif
  return (f->owned >> cube_face(f, x, y, z)) & 1u;
}

// A whole cube in one launch (pcf.cl): each face's world -> texture NDC, +x -x +y -y +z -z; all
// zero for a face not rendered, whose pixels are then off every map and lit.
typedef struct {
  float16 to_ndc[6];
} cube_ndc_t;

// Outside a spot light's cone nothing is lit, receiver or not.
inline bool outside_spot_cone(float3 x, const light_t* l) {
  return l->kind == LIGHT_SPOT &&
         dot(normalize(x - l->position.xyz), l->axis.xyz) < l->cos_half_cone;
}

// The share of an area light's disk above the horizon of the side of a receiver the camera sees
// (unit normal n, facing the camera). The soft filters cap their filtered value by it: a cap,
// not a product, because where the receiver casts too the map already darkens its own grazing
// side, and a product counted that twice. It is 0 where the side faces away from the whole disk
// (its own, attached shadow whatever a map says: near the terminator the slope bias grows without
// bound and would light it), 1 where it faces all of it, and in between the disk's segment above
// the tangent plane. The disk is seen from x at unit distance with radius r, its centre at
// elevation e: the horizon crosses it t = tan(e) / r radii from the centre, and the share above
// is 1 - (acos t - t sqrt(1 - t^2)) / pi, as the area-light oracle's samples count it. With no
// disk (r = 0) it steps at edge-on, where it is 1. The hard test and PCF (pcf.cl, unrolled)
// darken every side not facing the light.
inline float disk_above_horizon(float3 x, float3 n, const light_t* l) {
  float3 to_light = l->kind == LIGHT_DIRECTIONAL ? -l->axis.xyz : l->position.xyz - x;
  float dist = length(to_light);
  float s = dot(n, to_light) / dist;  // sin(e)
  float r = l->kind == LIGHT_DIRECTIONAL ? l->disk : l->disk / dist;
  float rc = r * sqrt(fmax(1.0f - s * s, 0.0f));  // r cos(e): |t| >= 1 where |s| >= rc
  if (s >= rc) return 1.0f;
  if (s <= -rc) return 0.0f;
  float t = s / rc;
  return 1.0f - (acos(t) - t * sqrt(1.0f - t * t)) * M_1_PI_F;
}

// floor() as an int for |x| < 2^31, select-only so that it vectorizes.
inline int floor_int(float x) {
  int t = (int)x;
  return (float)t > x ? t - 1 : t;
}

// A camera-view pixel's view depth: its distance from eye e along the unit forward axis f. In
// fma steps, so that the depth-range pass (reduce.cl) and the quality probe's hard test (pcf.cl,
// VIEW_DEPTH) give the same bits however each is vectorized; scalars, so that a loop calling it
// still vectorizes.
inline float view_depth(float x, float y, float z, float ex, float ey, float ez, float fx, float fy,
                        float fz) {
  return fma(z - ez, fz, fma(y - ey, fy, (x - ex) * fx));
}

// Whether a camera-view pixel receives shadows and so counts towards the view-depth range: seen
// (position not NaN) with a G-buffer normal.w not 0 (nor NaN).
inline int receives_shadows(float x, float y, float z, float w) {
  return !isnan(x) & !isnan(y) & !isnan(z) & (w != 0.0f) & !isnan(w);
}

// The min of lo[0, n) and the max of hi[0, n), n a power of two, halving the arrays in place:
// reduced one running pair at a time, every fmin waits on the last, which in the view-depth
// reductions cost more than reading the pixels they reduce.
inline float2 min_max_halving(float* lo, float* hi, uint n) {
  for (uint span = n / 2; span > 0; span /= 2)
    for (uint l = 0; l < span; ++l) {
      lo[l] = fmin(lo[l], lo[l + span]);
      hi[l] = fmax(hi[l], hi[l + span]);
    }
  return (float2)(lo[0], hi[0]);
}
