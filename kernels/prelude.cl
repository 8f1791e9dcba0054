// Shared by every program: matrix helpers and the records the host lays out in
// server/engine/device_types.hpp (keep the two in step; the host static_asserts the sizes).
//
// The same bits on every device (issue 41). OpenCL lets each compiler fuse a * b + c into one
// rounding or not: contraction is off for every program, and fma() says where a fused step is
// meant. Float division and sqrt are correctly rounded (the program cache's
// -cl-fp32-correctly-rounded-divide-sqrt). No native_ or half_ math, no float atomics.
// `#pragma clang loop` and `#pragma unroll` are only hints: a compiler that does not know them
// ignores them, as C99 (6.10.6) has it.
#pragma OPENCL FP_CONTRACT OFF

// dot, cross, length, normalize, mix and hypot, spelled out: OpenCL bounds their error but lets
// each device choose its steps. Products and lerps in fma steps (one rounding, and one
// instruction where contraction used to fuse them).
inline float dot3(float3 a, float3 b) {
  return fma(a.z, b.z, fma(a.y, b.y, a.x * b.x));
}
inline float3 cross3(float3 a, float3 b) {
  return (float3)(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
inline float length3(float3 v) {
  return sqrt(dot3(v, v));
}
// The zero vector stays zero, as normalize() leaves it. One reciprocal: a third of the cost.
inline float3 normalize3(float3 v) {
  float l = length3(v);
  return l > 0.0f ? v * (1.0f / l) : v;
}
// Two unit tangents of the plane of unit normal n, (t1, t2, n) right-handed; the same for the
// same n wherever they are computed.
inline void surface_tangents(float3 n, float3* t1, float3* t2) {
  float3 e = fabs(n.x) < 0.9f ? (float3)(1.0f, 0.0f, 0.0f) : (float3)(0.0f, 1.0f, 0.0f);
  *t1 = normalize3(cross3(n, e));
  *t2 = cross3(n, *t1);
}

inline float lerp(float a, float b, float t) {
  return fma(b - a, t, a);
}
// a x + b y + c z (+ d): a row of a matrix times a point, in fma steps, for the scalar loops.
inline float row3(float a, float b, float c, float x, float y, float z) {
  return fma(c, z, fma(b, y, a * x));
}
inline float row4(float a, float b, float c, float d, float x, float y, float z) {
  return fma(c, z, fma(b, y, fma(a, x, d)));
}

// sin and cos of a in [0, 2 pi) without branches: Taylor to degree 13/12 at h = a/2 - pi/2 in
// [-pi/2, pi/2] (error < 1e-7), then the double angle: sin a = -sin 2h, cos a = -cos 2h. Horner in
// fma steps; sin() and cos() may differ by 4 ulp from device to device.
inline float taylor_sin(float h, float h2) {
  float p = fma(h2, 1.0f / 6227020800.0f, -1.0f / 39916800);
  p = fma(h2, p, 1.0f / 362880);
  p = fma(h2, p, -1.0f / 5040);
  p = fma(h2, p, 1.0f / 120);
  p = fma(h2, p, -1.0f / 6);
  return h * fma(h2, p, 1.0f);
}
inline float taylor_cos(float h2) {
  float p = fma(h2, 1.0f / 479001600.0f, -1.0f / 3628800);
  p = fma(h2, p, 1.0f / 40320);
  p = fma(h2, p, -1.0f / 720);
  p = fma(h2, p, 1.0f / 24);
  p = fma(h2, p, -0.5f);
  return fma(h2, p, 1.0f);
}
// sin a, with cos a in *c (a in [0, 2 pi)).
inline float sin_cos(float a, float* c) {
  float h = 0.5f * a - 1.5707963f, h2 = h * h;
  float hs = taylor_sin(h, h2), hc = taylor_cos(h2);
  *c = 2.0f * hs * hs - 1.0f;
  return -2.0f * hs * hc;
}

// log2, exp2, exp and acos from exact steps (frexp, ldexp, rint, correctly rounded sqrt) and
// polynomials in fma steps: OpenCL lets the builtins be off by 3-4 ulp, each device its own way.
// Good to a few ulp; the builtins are left only the exact cases (0, infinities, NaN) and ranges
// no caller reaches.
inline float portable_log2(float x) {
  if (!(x > 0.0f) || isinf(x)) return log2(x);
  int e;
  float m = frexp(x, &e);  // [0.5, 1)
  if (m < 0.70710678f) {
    m *= 2.0f;
    e -= 1;
  }
  // ln m = 2 atanh(s), s = (m - 1) / (m + 1) in [-0.172, 0.172]: odd series to s^9.
  float s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
  float q = fma(s2, 1.0f / 9, 1.0f / 7);
  q = fma(s2, q, 1.0f / 5);
  q = fma(s2, q, 1.0f / 3);
  q = fma(s2, q, 1.0f);
  return fma(2.0f * s * q, M_LOG2E_F, (float)e);
}
inline float portable_exp2(float x) {
  if (!(fabs(x) < 126.0f)) return exp2(x);
  float n = rint(x), u = (x - n) * M_LN2_F;  // x - n exact, in [-1/2, 1/2]
  // e^u, |u| <= 0.35: Taylor to u^7.
  float p = fma(u, 1.0f / 5040, 1.0f / 720);
  p = fma(u, p, 1.0f / 120);
  p = fma(u, p, 1.0f / 24);
  p = fma(u, p, 1.0f / 6);
  p = fma(u, p, 0.5f);
  p = fma(u, p, 1.0f);
  p = fma(u, p, 1.0f);
  return ldexp(p, (int)n);
}
inline float portable_exp(float x) {
  return portable_exp2(x * M_LOG2E_F);
}
// Abramowitz & Stegun 4.4.46 (error <= 2e-8 before float rounding), x in [-1, 1].
inline float portable_acos(float x) {
  float a = fabs(x);
  float p = fma(a, -0.0012624911f, 0.0066700901f);
  p = fma(a, p, -0.0170881256f);
  p = fma(a, p, 0.0308918810f);
  p = fma(a, p, -0.0501743046f);
  p = fma(a, p, 0.0889789874f);
  p = fma(a, p, -0.2145988016f);
  p = fma(a, p, 1.5707963050f);
  float r = sqrt(1.0f - a) * p;
  return x < 0.0f ? M_PI_F - r : r;
}

// A 4x4 matrix travels as float16 in GLM's column-major order: s0123 is the first column.
inline float4 mul_m4(const float16 m, const float4 v) {
  return fma(m.scdef, (float4)(v.w),
             fma(m.s89ab, (float4)(v.z), fma(m.s4567, (float4)(v.y), m.s0123 * v.x)));
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

// The shadow atlas' tile over texel (x, y): (x, y, size, 1), or zeros where none is, from a grid
// of `cell`-texel cells (every tile's corner and size are multiples of cell; the atlas is `width`
// texels wide). Tiles are sized per instance, so a texel's tile is looked up, not divided out.
inline uint4 atlas_tile_at(global const uint4* cells, uint cell, uint width, uint x, uint y) {
  return cells[(y / cell) * (width / cell) + x / cell];
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
  float3 t1 = fabs(n.x) < 0.9f ? cross3(n, (float3)(1, 0, 0)) : cross3(n, (float3)(0, 1, 0));
  t1 = normalize3(t1);
  float3 t2 = cross3(n, t1);
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

// Which camera pixels one map of a cube decides (engine/light/light_space.hpp, CubeFaces): the face
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
         dot3(normalize3(x - l->position.xyz), l->axis.xyz) < l->cos_half_cone;
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
  float dist = length3(to_light);
  float s = dot3(n, to_light) / dist;  // sin(e)
  float r = l->kind == LIGHT_DIRECTIONAL ? l->disk : l->disk / dist;
  float rc = r * sqrt(fmax(1.0f - s * s, 0.0f));  // r cos(e): |t| >= 1 where |s| >= rc
  if (s >= rc) return 1.0f;
  if (s <= -rc) return 0.0f;
  float t = s / rc;
  return 1.0f - (portable_acos(t) - t * sqrt(1.0f - t * t)) * M_1_PI_F;
}

// floor() as an int for |x| < 2^31, select-only so that it vectorizes.
inline int floor_int(float x) {
  int t = (int)x;
  return (float)t > x ? t - 1 : t;
}

// A camera-view pixel's view depth: its distance from eye e along the unit forward axis f. In
// fma steps, so that the depth-range pass (depth_range.cl) and the quality probe's hard test
// (pcf.cl, VIEW_DEPTH) give the same bits however each is vectorized; scalars, so that a loop
// calling it still vectorizes.
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
