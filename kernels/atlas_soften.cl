// The soft shadow atlas (FILTER_ATLAS_SAT and FILTER_ATLAS_MIP; engine/passes/atlas_soften.hpp):
// PCSS's penumbra at every atlas texel (pcss.cl's pcss_penumbra) filtered over the prefiltered
// hard atlas once per light, then one lookup per camera pixel.
//
// Shadow-atlas lookups (seed 004, 2.3): PCSS's steps 1 and 2 (pcss.cl), then the prefiltered hard
// atlas read over the penumbra instead of PCF. Every quantity involved belongs to the surface
// point, not to the camera, so all of it runs once per atlas texel when the light's atlas is made
// (pcss_penumbra, then atlas_soften), and a camera pixel pays one bilinear lookup of the result
// (atlas_lookup). PCSS filters a disk of the penumbra's radius in the map; on the surface that disk
// is an ellipse, stretched along the light where it grazes, and in the atlas an ellipse again
// (atlas_footprint). The paper's l_lod (eq. 4-5) is the scalar form of this map: the ratio of the
// two texels' areas, a disk of their mean scale, too wide across a grazing light's shadows and too
// short along them (issue 43). Both filters keep to the filtered texel's chart (a chart id per
// texel from the bake), as lightmap bakers filter: texels of other charts are not its neighbours on
// the surface, nor are gutter texels surface points. SAT: the mean over the surface texels of the
// ellipse, as strips of boxes, within the instance's tile, halved until no strip holds another
// chart; mips: trilinear probes along the ellipse's long axis at the level of its short one
// (anisotropic filtering), of a chain that records each texel's chart (-1 where charts meet),
// reading only the chart's own texels, finer where a level has none around a probe.

#pragma OPENCL EXTENSION cl_khr_fp64 : enable  // the atlas' summed-area tables

// The GPU shape (engine/passes/pixel_shape.hpp) builds this file with -DPIXEL_CHUNK=1 and launches
// it in work-groups: a work-item per pixel or texel, each one's arithmetic as here.
#ifdef PIXEL_CHUNK
#define TEXEL_CHUNK PIXEL_CHUNK
#else
#define PIXEL_CHUNK 64   // pixels or texels per work-item of the soft kernels
#define TEXEL_CHUNK 256  // texels per work-item of the chart kernels
#endif

#define MAX_STRIPS 16  // boxes across an ellipse (atlas_sat), probes along it (atlas_mip)

// Box sums over texels [x0, x1] x [y0, y1] of every channel of a SAT of two or three: each
// corner read once for all of them.
#define SAT_BOX(N)                                                                          \
  inline double##N sat_box##N(global const double* sat, uint width, int x0, int y0, int x1, \
                              int y1) {                                                     \
    double##N v = vload##N((size_t)y1 * width + x1, sat);                                   \
    if (x0 > 0) v -= vload##N((size_t)y1 * width + x0 - 1, sat);                            \
    if (y0 > 0) v -= vload##N((size_t)(y0 - 1) * width + x1, sat);                          \
    if (x0 > 0 && y0 > 0) v += vload##N((size_t)(y0 - 1) * width + x0 - 1, sat);            \
    return v;                                                                               \
  }
SAT_BOX(2)
SAT_BOX(3)

// The penumbra's disk of radius `radius` (light units) at surface point x (normal n) in atlas
// texels: the ellipse {p : p^T S^-1 p <= 1}, S = (xx, yy, xy) = radius^2 A A^T, A = B^-1 and B
// the light units one atlas texel step moves along x and along y (the map's Jacobian along the
// texel's axes, atlas_resolve's, over `scale`). Not finite where the surface is edge-on to the
// light.
inline float3 footprint_at(const shadow_lookup_t* lookup, float2 scale, float3 x, float3 n,
                           float4 axes, float radius) {
  float3 t1, t2;
  surface_tangents(n, &t1, &t2);
  float3 ax = axes.x * t1 + axes.y * t2, ay = axes.z * t1 + axes.w * t2;
  float4 c = mul_m4(lookup->to_ndc, (float4)(x, 1.0f));
  float4 dx = mul_m4(lookup->to_ndc, (float4)(ax, 0.0f));
  float4 dy = mul_m4(lookup->to_ndc, (float4)(ay, 0.0f));
  float k = (float)lookup->map_size / (c.w * c.w);
  float2 bx = (dx.xy * c.w - c.xy * dx.w) * k / scale;
  float2 by = (dy.xy * c.w - c.xy * dy.w) * k / scale;
  float s = radius / (bx.x * by.y - by.x * bx.y);
  float2 r0 = (float2)(by.y, -by.x) * s, r1 = (float2)(-bx.y, bx.x) * s;  // A's rows, times radius
  return (float3)(fma(r0.x, r0.x, r0.y * r0.y), fma(r1.x, r1.x, r1.y * r1.y),
                  fma(r0.x, r1.x, r0.y * r1.y));
}

// Sums over texels [s0, s1] along the strips' axis and [t0, t1] across (x first where
// `along_x`) within the tile (texels [lo, lo + hi]): the visibility and the surface texels used
// (those dark by a rule left out: atlas_dark_by_rule) into v, and whether another chart than h is
// among them.
inline int atlas_strip(global const double* sat, global const double* moments, uint width,
                       int along_x, int s0, int s1, int t0, int t1, int lo_x, int lo_y, int hi,
                       double h, double* v, double* used) {
  int x0 = along_x ? s0 : t0, x1 = along_x ? s1 : t1, y0 = along_x ? t0 : s0,
      y1 = along_x ? t1 : s1;
  x0 = clamp(x0, lo_x, lo_x + hi), x1 = clamp(x1, lo_x, lo_x + hi);
  y0 = clamp(y0, lo_y, lo_y + hi), y1 = clamp(y1, lo_y, lo_y + hi);
  double2 box = sat_box2(sat, width, x0, y0, x1, y1);    // visibility, coverage
  double3 m = sat_box3(moments, width, x0, y0, x1, y1);  // h, h^2, dark by rule
  *v += box.x;
  *used += box.y - m.z;
  return m.y - 2.0 * h * m.x + h * h * box.y >= 0.5;
}

// The mean visibility of chart h's surface texels in the ellipse S (atlas_footprint's) around
// texel (i, j), within its tile (texels [lo, lo + hi]), those dark by a rule left out, from the SAT
// of (visibility, coverage) and that of (h, h^2, attached) (atlas_chart_moments). The ellipse is
// cut across its longer extent (x or y) into strips, each a box of the ellipse's height at the
// strip's middle about its centre line. While a strip holds another chart, sum (h' - h)^2 = m2 - 2
// h m1 + h^2 n > 0 (exact: integers in double), the ellipse is halved; under half a texel it is the
// texel itself. NaN when no texel of it is left.
inline float atlas_chart_ellipse(global const double* sat, global const double* moments, uint width,
                                 int i, int j, float3 S, int lo_x, int lo_y, int hi, double h) {
  int along_x = S.x >= S.y;
  float ext = sqrt(along_x ? S.x : S.y);  // half the extent along the strips' axis
  float slope = S.z / (along_x ? S.x : S.y), height = sqrt(fmax(S.x * S.y - S.z * S.z, 0.0f)) / ext;
  // No wider than the tile: edge-on to the light, the ellipse is infinite (NaN: fmin takes the
  // tile).
  ext = fmin(ext, (float)(hi + 1)), height = fmin(height, (float)(hi + 1));
  if (!isfinite(slope)) slope = 0.0f;
  float c_s = (float)(along_x ? i : j) + 0.5f, c_t = (float)(along_x ? j : i) + 0.5f;
  for (float f = 1.0f;; f *= 0.5f) {
    float e = ext * f, hf = height * f;
    double v = 0.0, used = 0.0;
    if (e < 0.5f && hf < 0.5f) {
      atlas_strip(sat, moments, width, 1, i, i, j, j, lo_x, lo_y, hi, h, &v, &used);
      return used > 0.5 ? (float)(v / used) : NAN;
    }
    // Strips about as wide as the ellipse is high (|slope| <= 1: the centre line moves no more
    // than that across one); past MAX_STRIPS, that many spread evenly along it, with gaps. Each
    // holds the texels whose centres it covers, so that it is as wide as the ellipse on average
    // (taking every texel it touched widened it by one: a sub-texel ellipse read three), and at
    // least the texel under its middle where the ellipse passes between centres.
    int needed = (int)ceil(4.0f * e / fmax(hf, 1.0f)), n = clamp(needed, 1, MAX_STRIPS);
    float step = 2.0f * e / (float)n, w = needed > n ? fmax(0.5f * hf, 0.5f) : step;
    int other = 0;
    for (int k = 0; k < n && !other; ++k) {
      float mid = -e + ((float)k + 0.5f) * step, m = mid / e;
      float half_t = hf * sqrt(fmax(1.0f - m * m, 0.0f)), centre = c_t + slope * mid;
      // Centres in [mid - w / 2, mid + w / 2): touching strips share none.
      int s0 = (int)ceil(c_s + mid - 0.5f * w - 0.5f),
          s1 = (int)ceil(c_s + mid + 0.5f * w - 0.5f) - 1;
      int t0 = (int)ceil(centre - half_t - 0.5f), t1 = (int)floor(centre + half_t - 0.5f);
      if (s1 < s0) {
        if (needed == n) continue;  // its neighbours hold the centres
        s0 = s1 = (int)floor(c_s + mid);
      }
      if (t1 < t0) t0 = t1 = (int)floor(centre);
      other =
          atlas_strip(sat, moments, width, along_x, s0, s1, t0, t1, lo_x, lo_y, hi, h, &v, &used);
    }
    if (!other) return used > 0.5 ? (float)(v / used) : NAN;
  }
}

// Chart h's mean visibility at level k of the chart chain (float4 per texel: visibility,
// surface texels under it, chart, 0) around continuous level-0 texel q, bilinear over the taps
// that hold chart h alone; `weight` 0 when none does.
inline float atlas_chart_bilinear(global const float4* chain, global const uint4* levels, uint k,
                                  float2 q, float h, float* weight) {
  uint4 l = levels[k];  // width, height, offset into chain
  uint4 l0 = levels[0];
  float2 p = q * (float2)((float)l.x / l0.x, (float)l.y / l0.y) - 0.5f;
  float2 f = p - floor(p);
  int i0 = (int)floor(p.x), j0 = (int)floor(p.y);
  float sum = 0.0f, w_sum = 0.0f;
  for (int k2 = 0; k2 < 4; ++k2) {
    int i = clamp(i0 + (k2 & 1), 0, (int)l.x - 1), j = clamp(j0 + (k2 >> 1), 0, (int)l.y - 1);
    float w = ((k2 & 1) ? f.x : 1.0f - f.x) * ((k2 >> 1) ? f.y : 1.0f - f.y);
    float4 c = chain[l.z + (size_t)j * l.x + i];
    if (c.y > 0.0f && c.z == h) sum += w * c.x, w_sum += w;
  }
  *weight = w_sum;
  return w_sum > 0.0f ? sum / w_sum : NAN;
}

// Chart h's trilinear read of the chain at `mip` around q: a level with none of the chart
// around q reads the next finer one (level 0 holds the texel itself). NaN where none has it.
inline float atlas_chart_trilinear(global const float4* chain, global const uint4* levels,
                                   float mip, float2 q, float h) {
  uint k0 = (uint)floor(mip);
  float f = mip - (float)k0, w0, w1 = 0.0f;
  float v0 = atlas_chart_bilinear(chain, levels, k0, q, h, &w0);
  while (w0 == 0.0f && k0 > 0) v0 = atlas_chart_bilinear(chain, levels, --k0, q, h, &w0), f = 0.0f;
  float v1 = f > 0.0f ? atlas_chart_bilinear(chain, levels, k0 + 1, q, h, &w1) : v0;
  return w1 > 0.0f ? lerp(v0, v1, f) : v0;
}

// The ellipse S's eigenvalues: its long and short semi-axes squared, the short at least 0.
inline void ellipse_eigen(float3 S, float* big, float* small) {
  float mean = 0.5f * (S.x + S.y), half_diff = 0.5f * (S.x - S.y);
  float d = sqrt(fma(half_diff, half_diff, S.z * S.z));
  *big = mean + d, *small = fmax(mean - d, 0.0f);
}

// Chart h's mean visibility over the ellipse S (atlas_footprint's) around continuous texel q,
// from the chart chain (levels 0 .. level_count): probes spaced along its long axis at the
// level of its short one, as anisotropic texture filtering does, those that find none of the
// chart left out; within `size` (the tile's). NaN when none finds it. Sized to the ellipse's
// spread (its variance along each axis, a quarter of the semi-axis squared): a bilinear read at
// a level of texels of side t spreads t^2 / 4 (the texel's box and the tent), so the short
// semi-axis b reads level log2(b) (0 at least: then the read alone spreads 1 / 4), and n probes
// evenly over [-T, T] add T^2 (n + 1) / (3 (n - 1)) along the long axis, up to its a^2 / 4.
// (Level log2(2 b), a texel as wide as the ellipse, blurred twice as wide.)
inline float atlas_chart_probes(global const float4* chain, global const uint4* levels,
                                uint level_count, float2 q, float3 S, float size, float h) {
  float big, small;
  ellipse_eigen(S, &big, &small);
  float a = sqrt(big), b = sqrt(small);    // the semi-axes
  float2 axis = (float2)(S.z, big - S.x);  // the long axis' direction
  float length = sqrt(fma(axis.x, axis.x, axis.y * axis.y));
  axis = length > 0.0f && isfinite(length)
             ? axis / length
             : (S.x >= S.y ? (float2)(1.0f, 0.0f) : (float2)(0.0f, 1.0f));
  a = fmin(a, size), b = fmin(b, a);  // edge-on to the light: no wider than the tile
  float short_half = fmax(b, 0.5f);
  int n = clamp((int)ceil(a / short_half), 1, MAX_STRIPS);
  float mip = clamp(portable_log2(short_half), 0.0f, (float)level_count);
  float side = portable_exp2(mip);  // the level's texel, in level-0 texels
  float spread =
      n == 1 ? 0.0f
             : sqrt(0.75f * (float)(n - 1) / (float)(n + 1) * fmax(a * a - side * side, 0.0f));
  float sum = 0.0f;
  int found = 0;
  for (int k = 0; k < n; ++k) {
    float t = n == 1 ? 0.0f : spread * (2.0f * (float)k / (float)(n - 1) - 1.0f);
    float v = atlas_chart_trilinear(chain, levels, mip, q + t * axis, h);
    if (!isnan(v)) sum += v, ++found;
  }
  return found > 0 ? sum / (float)found : NAN;
}

// The footprint's long semi-axis is at most MAX_STRETCH times its short one: as if the light were
// never lower than 7 degrees over the surface. A tangent plane stretches a grazing light's disk
// without bound (edge-on, over the whole tile), though what lies there is rarely that plane:
// capped at 4 / 8 / 16 / none, the chess' and forest's mean error over their views was 0.0030 /
// 0.0031 / 0.0035 / 0.0035 and 0.0175 / 0.0166 / 0.0162 / 0.0214 (shadow-atlas-bench
// --standard; PCSS 0.0022 and 0.0154).
#define MAX_STRETCH 8.0f
inline float3 capped_stretch(float3 S) {
  float big, small;
  ellipse_eigen(S, &big, &small);
  float cap = MAX_STRETCH * MAX_STRETCH * small;
  if (!(big > cap)) return S;  // NaN (edge-on): the filters keep to the tile
  // S = small I + (big - small) e e^T with e the long axis: the same with big -> cap.
  float f = (cap - small) / (big - small);
  return (float3)(small + (S.x - small) * f, small + (S.y - small) * f, S.z * f);
}

// The footprint (footprint_at, three floats a texel, capped_stretch) of every atlas texel whose
// penumbra (`half_width`, light units) is filtered, of its radius or half a map texel if more
// (not finite where the surface is edge-on to the light); NaN elsewhere. `axes`:
// atlas_resolve's.
kernel void atlas_footprint(global const float* position, global const float4* normal,
                            global const float4* axes, global const float* half_width,
                            uint texel_count, shadow_lookup_t lookup, float2 scale,
                            global float* footprint) {
  float min_radius = 0.5f / fmin(scale.x, scale.y);
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, texel_count);
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position), S = (float3)(NAN);
    if (!isnan(x.x) && half_width[p] > 0.0f)
      S = capped_stretch(
          footprint_at(&lookup, scale, x, normal[p].xyz, axes[p], fmax(half_width[p], min_radius)));
    vstore3(S, p, footprint);
  }
}

// The soft atlas' texels: the visibility in the low 16 bits (unorm: steps of 1.5e-5) and the
// chart (1 .. 2047) in the high ones; 0 where no surface is.
inline uint atlas_soft(float vis, uint chart) {
  return chart << 16 | (uint)(clamp(vis, 0.0f, 1.0f) * 65535.0f + 0.5f);
}

// Once per light, at every atlas texel (rows of `width`; each texel's tile from `cells` of `cell`
// texels, atlas_tile_at: tiles are sized per instance): the soft visibility there, 1 where the
// search found no blocker, packed with the texel's chart (atlas_soft(): a frame's lookup gathers
// one word a tap). The filter, where the search found a blocker (`half_width` > 0): the
// penumbra's disk as an ellipse in the atlas (`footprint`, atlas_footprint's). `charts`:
// atlas_resolve's.
// use_sat: the SATs of (visibility, coverage) and of the chart moments, else the chart chain
// (levels[0 .. level_count]).
kernel void atlas_soften(global const float* position, global const float* half_width,
                         global const float* footprint, global const float* charts,
                         uint texel_count, uint width, global const uint4* cells, uint cell,
                         int use_sat, global const double* sat, global const double* moments,
                         global const float4* chain, global const uint4* levels, uint level_count,
                         global uint* soft) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, texel_count);
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    float vis = 1.0f, h = charts[p];
    if (isnan(x.x)) {
      vis = NAN;
    } else if (half_width[p] > 0.0f) {
      float3 S = vload3(p, footprint);
      int i = (int)(p % width), j = (int)(p / width);
      uint4 tile = atlas_tile_at(cells, cell, width, (uint)i, (uint)j);
      float found = use_sat ? atlas_chart_ellipse(sat, moments, width, i, j, S, (int)tile.x,
                                                  (int)tile.y, (int)tile.z - 1, (double)h)
                            : atlas_chart_probes(chain, levels, level_count,
                                                 (float2)((float)i + 0.5f, (float)j + 0.5f), S,
                                                 (float)tile.z, h);
      vis = isnan(found) ? 1.0f : found;
    }
    soft[p] = isnan(vis) ? 0u : atlas_soft(vis, (uint)h);
  }
}

// Per camera pixel: its UV from the camera raster's primitive (`ids`, `draws`), its tile
// (`tiles`: per scene instance x, y, size, 1 if it has one), and the soft atlas (atlas_soften)
// there, bilinear within the tile over the taps of the chart the point lies in (the texel
// holding it), empty texels and other charts left out. `uvs`: the scene's UVs in vertex
// order. Two loops over the strip: the first finds each pixel's texel (branches; neighbouring
// pixels mostly see the same triangle, whose set-up is computed once per run of equal ids), the
// second reads the atlas without branches so that LLVM vectorizes its gathers (one loop with
// branches: 10.5 ms against 8.5 at 1280x720, shadow-atlas-bench).
kernel void atlas_lookup(global const float* position, global const float4* normal,
                         uint pixel_count, light_t light, global const uint* ids,
                         global const draw_t* draws, uint draw_count, global const float* positions,
                         global const uint* indices, global const float* uvs,
                         global const uint4* tiles, global const uint* soft, uint atlas_width,
                         global float* visibility) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint count = min((uint)PIXEL_CHUNK, pixel_count - min(first, pixel_count));
  // Per pixel: its continuous atlas texel, its tile's first texel and last offset, and its
  // visibility where no lookup is needed (-1: look up).
  float qx[PIXEL_CHUNK], qy[PIXEL_CHUNK], fixed[PIXEL_CHUNK], above[PIXEL_CHUNK];
  int lo_x[PIXEL_CHUNK], lo_y[PIXEL_CHUNK], hi[PIXEL_CHUNK];
  uint held = 0xffffffffu;
  float3 a = (float3)(0.0f), nt = (float3)(0.0f), ab = nt, ac = nt;
  float2 ua = (float2)(0.0f), du = ua, dv = ua;
  float inv = 0.0f;
  uint4 tile = (uint4)(0);
  for (uint k = 0; k < count; ++k) {
    uint p = first + k;
    float3 x = vload3(p, position);
    float vis = 1.0f;
    above[k] = 1.0f;
    qx[k] = qy[k] = 0.5f, lo_x[k] = lo_y[k] = hi[k] = 0;
    if (isnan(x.x)) {
      vis = NAN;
    } else if (outside_spot_cone(x, &light)) {
      vis = 0.0f;
    } else if (normal[p].w != 0.0f &&
               (above[k] = disk_above_horizon(x, normal[p].xyz, &light)) == 0.0f) {
      vis = 0.0f;
    } else if (normal[p].w != 0.0f) {
      uint id = ids[p];
      if (id != held) {
        global const draw_t* d = draws + find_draw(draws, draw_count, id, 1);
        float3 b, c;
        world_triangle(positions, indices, d, id, &a, &b, &c);
        ab = b - a, ac = c - a, nt = cross3(ab, ac), inv = 1.0f / dot3(nt, nt);
        global const uint* idx = indices + d->index_base + 3 * (id - d->out_triangle_base);
        ua = vload2(d->vertex_base + idx[0], uvs);
        du = vload2(d->vertex_base + idx[1], uvs) - ua;
        dv = vload2(d->vertex_base + idx[2], uvs) - ua;
        tile = tiles[d->instance];
        held = id;
      }
      if (tile.w) {
        // x's barycentrics in its triangle give its UV, and its atlas texel q.
        float lb = dot3(cross3(x - a, ac), nt) * inv, lc = dot3(cross3(ab, x - a), nt) * inv;
        float2 uv = clamp(ua + lb * du + lc * dv, 0.0f, 1.0f);
        qx[k] = (float)tile.x + uv.x * (float)tile.z, qy[k] = (float)tile.y + uv.y * (float)tile.z;
        lo_x[k] = (int)tile.x, lo_y[k] = (int)tile.y, hi[k] = (int)tile.z - 1;
        vis = -1.0f;
      }
    }
    fixed[k] = vis;
  }
  for (uint k = 0; k < count; ++k) {
    float px = qx[k] - 0.5f, py = qy[k] - 0.5f;
    int i0 = floor_int(px), j0 = floor_int(py);
    float fx = px - (float)i0, fy = py - (float)j0;
    int i1 = min(max(i0 + 1, lo_x[k]), lo_x[k] + hi[k]),
        j1 = min(max(j0 + 1, lo_y[k]), lo_y[k] + hi[k]);
    i0 = min(max(i0, lo_x[k]), lo_x[k] + hi[k]), j0 = min(max(j0, lo_y[k]), lo_y[k] + hi[k]);
    uint s00 = soft[j0 * (int)atlas_width + i0], s10 = soft[j0 * (int)atlas_width + i1];
    uint s01 = soft[j1 * (int)atlas_width + i0], s11 = soft[j1 * (int)atlas_width + i1];
    // The point's chart (0: none, take any): that of the tap whose texel holds it.
    uint h = (fy < 0.5f ? (fx < 0.5f ? s00 : s10) : (fx < 0.5f ? s01 : s11)) >> 16;
    int u00 = s00 >> 16 != 0 && (h == 0 || s00 >> 16 == h);
    int u10 = s10 >> 16 != 0 && (h == 0 || s10 >> 16 == h);
    int u01 = s01 >> 16 != 0 && (h == 0 || s01 >> 16 == h);
    int u11 = s11 >> 16 != 0 && (h == 0 || s11 >> 16 == h);
    float w00 = u00 ? (1.0f - fx) * (1.0f - fy) : 0.0f, w10 = u10 ? fx * (1.0f - fy) : 0.0f;
    float w01 = u01 ? (1.0f - fx) * fy : 0.0f, w11 = u11 ? fx * fy : 0.0f;
    float sum = w00 * (float)(s00 & 0xffffu) + w10 * (float)(s10 & 0xffffu) +
                w01 * (float)(s01 & 0xffffu) + w11 * (float)(s11 & 0xffffu);
    float weight = w00 + w10 + w01 + w11;
    float found = weight > 0.0f ? sum / (65535.0f * weight) : 1.0f;  // no surface around: lit
    float f = fixed[k];
    float v = f == -1.0f ? found : f;
    visibility[first + k] = isnan(v) ? v : fmin(v, above[k]);
  }
}

// Whether the hard test darkens surface point x (normal n) by a rule alone (pcf.cl): the
// attached shadow (it faces away from the light's centre, or edge-on) or a spot's cone. That 0
// says nothing of occluders (PCSS reads the map there instead), and both rules are applied per
// camera pixel (disk_above_horizon and outside_spot_cone in atlas_lookup), so the atlas filters
// leave such texels out: a texel outside the cone would otherwise darken its lit neighbours
// inside, and a pixel's bilinear lookup blend the cone's edge over a texel.
inline int atlas_dark_by_rule(float3 x, float3 n, const light_t* l) {
  float3 travel = l->kind == LIGHT_DIRECTIONAL ? l->axis.xyz : x - l->position.xyz;
  return dot3(n, travel) >= 0.0f || outside_spot_cone(x, l);
}

// The chart of each surface texel (`charts`, atlas_resolve's) as the moments
// (h, h^2), and whether it is dark by a rule (atlas_dark_by_rule), 0 elsewhere, for a summed-area
// table that tells whether a box holds one chart only: sum (h - h_c)^2 over the box is 0 exactly
// when every surface texel in it is chart h_c (integers below 2^11: every sum is exact in double).
kernel void atlas_chart_moments(global const float* position, global const float4* normal,
                                global const float* charts, uint texel_count, light_t light,
                                global float* out) {
  uint first = get_global_id(0) * TEXEL_CHUNK;
  uint last = min(first + TEXEL_CHUNK, texel_count);
  for (uint texel = first; texel < last; ++texel) {
    float h = charts[texel];
    float attached =
        h > 0.0f && atlas_dark_by_rule(vload3(texel, position), normal[texel].xyz, &light) ? 1.0f
                                                                                           : 0.0f;
    vstore3((float3)(h, h * h, attached), texel, out);
  }
}

// Level 0 of the chart-aware mip chain of the atlas: per texel (visibility, surface texels
// under it, chart: 0 none, -1 more than one), from the hard atlas at surface texels only, and
// of them those dark by a rule left out (atlas_dark_by_rule; `charts`: atlas_resolve's).
kernel void atlas_chart_base(global const float* atlas, global const float* position,
                             global const float4* normal, global const float* charts,
                             uint texel_count, light_t light, global float4* out) {
  uint first = get_global_id(0) * TEXEL_CHUNK;
  uint last = min(first + TEXEL_CHUNK, texel_count);
  for (uint texel = first; texel < last; ++texel) {
    float v = atlas[texel], h = charts[texel];
    int used = h != 0.0f && !isnan(v) &&
               !atlas_dark_by_rule(vload3(texel, position), normal[texel].xyz, &light);
    out[texel] = used ? (float4)(v, 1.0f, h, 0.0f) : (float4)(0.0f);
  }
}

// One level down (w x h -> w2 x h2, offsets in texels of `chain`): each texel the mean visibility
// of the surface texels of its 2x2 children, their count, and their chart if they share one (-1
// where charts meet: the lookup does not read such a texel).
kernel void atlas_chart_mip(global float4* chain, uint src_offset, uint w, uint h, uint dst_offset,
                            uint w2, uint h2) {
  uint first = get_global_id(0) * TEXEL_CHUNK;
  uint last = min(first + TEXEL_CHUNK, w2 * h2);
  for (uint texel = first; texel < last; ++texel) {
    uint i = texel % w2, j = texel / w2;
    float sum = 0.0f, count = 0.0f, chart = 0.0f;
    for (uint k = 0; k < 4; ++k) {
      uint x = 2 * i + (k & 1), y = 2 * j + (k >> 1);
      if (x >= w || y >= h) continue;
      float4 c = chain[src_offset + y * w + x];
      if (c.y == 0.0f) continue;
      sum += c.x * c.y, count += c.y;
      chart = chart == 0.0f ? c.z : chart == c.z ? chart : -1.0f;
    }
    chain[dst_offset + texel] =
        count > 0.0f ? (float4)(sum / count, count, chart, 0.0f) : (float4)(0.0f);
  }
}
