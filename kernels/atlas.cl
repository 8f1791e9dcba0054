// Shadow atlases (PRODUCT_SHADOW_ATLAS): every receiving instance's triangles rasterized in its
// own UV space into its tile, as a G-buffer (world position and normal per texel) that the
// visibility passes filter like the camera's; then the gutter around the charts.
//
// Coverage is conservative: a texel belongs to a triangle whose interior holds the texel's
// centre (ties by a top-left rule, so a shared edge's texels go to one side), else to a
// triangle that merely touches the texel's square (thin triangles keep their texels), its
// point clamped into the triangle. Among equals the lowest triangle wins (atomic_min), so the
// result does not depend on the order of the work-items.

// The GPU shape (engine/passes/pixel_shape.hpp) builds this file with -DPIXEL_CHUNK=1: a
// work-item per triangle and per texel, in work-groups, each one's arithmetic as here.
#ifdef PIXEL_CHUNK
#define TRI_CHUNK PIXEL_CHUNK
#define TEXEL_CHUNK PIXEL_CHUNK
#else
#define TRI_CHUNK 64     // triangles per work-item of atlas_cover
#define TEXEL_CHUNK 256  // texels per work-item of the per-texel kernels
#endif
#define NO_OWNER 0xffffffffu
#define EDGE_ONLY 0x80000000u  // an owner key: touched, centre outside

// Triangle `t` (a primitive id over the draws) in its tile's texel coordinates, counter-
// clockwise (positive area); false when its UVs are outside [0, 1] or not finite.
inline int tile_triangle(global const uint* indices, global const float* uvs,
                         global const draw_t* d, global const uint4* tiles, uint draw, uint t,
                         float2* p) {
  global const uint* idx = indices + d->index_base + 3 * (t - d->out_triangle_base);
  uint4 tile = tiles[draw];
  int ok = 1;
  for (int k = 0; k < 3; ++k) {
    float2 uv = vload2(d->vertex_base + idx[k], uvs);
    ok &= isfinite(uv.x) && isfinite(uv.y) && uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f &&
          uv.y <= 1.0f;
    p[k] = (float2)((float)tile.x, (float)tile.y) + uv * (float)tile.z;
  }
  return ok;
}

// Exactly antisymmetric in (a, b), rounding included: the two triangles of a shared edge get
// opposite values at every point, so no texel centre near the edge is inside both (computed from
// each side's own vertex order, a 45-degree edge through texel centres was).
inline float edge(float2 a, float2 b, float2 q) {
  int swap = a.x > b.x || (a.x == b.x && a.y > b.y);
  float2 lo = swap ? b : a, hi = swap ? a : b;
  float e = (hi.x - lo.x) * (q.y - lo.y) - (hi.y - lo.y) * (q.x - lo.x);
  return swap ? -e : e;
}

// Which of a tie on edge a->b counts as inside: of the two triangles sharing the edge (which
// see it in opposite directions) exactly one.
inline int owns_tie(float2 a, float2 b) {
  float2 d = b - a;
  return d.y > 0.0f || (d.y == 0.0f && d.x < 0.0f);
}

kernel void atlas_cover(global const uint* indices, global const float* uvs,
                        global const draw_t* draws, uint draw_count, global const uint4* tiles,
                        uint triangle_total, uint width, global uint* owner,
                        global uint* inside_count, global uint* flags) {
  uint first = get_global_id(0) * TRI_CHUNK;
  uint last = min(first + TRI_CHUNK, triangle_total);
  for (uint t = first; t < last; ++t) {
    uint di = find_draw(draws, draw_count, t, 1);
    global const draw_t* d = draws + di;
    float2 p[3];
    if (!tile_triangle(indices, uvs, d, tiles, di, t, p)) {
      atomic_min(flags, t);  // flags[0]: the first triangle with bad UVs
      continue;
    }
    float area = edge(p[0], p[1], p[2]);
    if (area == 0.0f) continue;  // no interior, no square to touch but a line
    if (area < 0.0f) {
      float2 s = p[1];
      p[1] = p[2], p[2] = s;
    }
    uint4 tile = tiles[di];
    float2 lo = fmin(fmin(p[0], p[1]), p[2]), hi = fmax(fmax(p[0], p[1]), p[2]);
    int x0 = max((int)tile.x, (int)floor(lo.x)), y0 = max((int)tile.y, (int)floor(lo.y));
    int x1 = min((int)(tile.x + tile.z), (int)ceil(hi.x)) - 1;
    int y1 = min((int)(tile.y + tile.z), (int)ceil(hi.y)) - 1;
    float2 d0 = p[1] - p[0], d1 = p[2] - p[1], d2 = p[0] - p[2];
    // How far each edge function rises from a texel's centre to its most inside corner.
    float r0 = 0.5f * (fabs(d0.x) + fabs(d0.y)), r1 = 0.5f * (fabs(d1.x) + fabs(d1.y));
    float r2 = 0.5f * (fabs(d2.x) + fabs(d2.y));
    int t0 = owns_tie(p[0], p[1]), t1 = owns_tie(p[1], p[2]), t2 = owns_tie(p[2], p[0]);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        float2 c = (float2)(x + 0.5f, y + 0.5f);
        float e0 = edge(p[0], p[1], c), e1 = edge(p[1], p[2], c), e2 = edge(p[2], p[0], c);
        // Outside, or touching along a line only.
        if (e0 + r0 <= 0.0f || e1 + r1 <= 0.0f || e2 + r2 <= 0.0f) continue;
        int inside = (e0 > 0.0f || (e0 == 0.0f && t0)) && (e1 > 0.0f || (e1 == 0.0f && t1)) &&
                     (e2 > 0.0f || (e2 == 0.0f && t2));
        uint texel = (uint)y * width + (uint)x;
        if (inside) atomic_inc(inside_count + texel);
        atomic_min(owner + texel, inside ? t : (t | EDGE_ONLY));
      }
  }
}

// Each texel's surface point: its owner's world position at the texel centre's barycentric
// coordinates (clamped into the triangle for touched texels), the triangle's normal, w = 1
// (the depth test), and the texel's axes on the surface (the world offsets of a texel step
// along x and y, in surface_tangents' frame: pcss.cl's footprint_at maps a penumbra through them);
// NaN where no triangle reaches. Also its chart (`chart_of` per triangle, >= 1; 0 where empty): the
// atlas filters keep to one chart. Counts texels whose centre two triangles hold (overlapping UVs)
// and keeps the first.
kernel void atlas_resolve(global const float* positions, global const uint* indices,
                          global const float* uvs, global const draw_t* draws, uint draw_count,
                          global const uint4* tiles, global const uint* owner,
                          global const uint* inside_count, global const uint* chart_of,
                          uint texel_count, uint width, global float* position_out,
                          global float4* normal_out, global float4* axes_out,
                          global float* chart_out, global uint* flags) {
  uint first = get_global_id(0) * TEXEL_CHUNK;
  uint last = min(first + TEXEL_CHUNK, texel_count);
  for (uint texel = first; texel < last; ++texel) {
    if (inside_count[texel] > 1) {
      atomic_inc(flags + 1);         // texels covered twice
      atomic_min(flags + 2, texel);  // the first of them
    }
    uint key = owner[texel];
    if (key == NO_OWNER) {
      vstore3((float3)(NAN), texel, position_out);
      normal_out[texel] = axes_out[texel] = (float4)(NAN);
      chart_out[texel] = 0.0f;
      continue;
    }
    uint t = key & ~EDGE_ONLY;
    uint di = find_draw(draws, draw_count, t, 1);
    global const draw_t* d = draws + di;
    float2 p[3];
    tile_triangle(indices, uvs, d, tiles, di, t, p);
    float2 c = (float2)((texel % width) + 0.5f, (texel / width) + 0.5f);
    float area = edge(p[0], p[1], p[2]);
    float3 l = (float3)(edge(p[1], p[2], c), edge(p[2], p[0], c), edge(p[0], p[1], c)) / area;
    l = fmax(l, 0.0f);  // a touched texel's centre may lie outside: the nearest corner side
    l /= l.x + l.y + l.z;
    float3 a, b, e;
    world_triangle(positions, indices, d, t, &a, &b, &e);
    vstore3(l.x * a + l.y * b + l.z * e, texel, position_out);
    float3 n = cross3(b - a, e - a);
    float len = length3(n);
    float3 unit = len > 0.0f ? n / len : (float3)(0.0f, 1.0f, 0.0f);
    normal_out[texel] = (float4)(unit, 1.0f);
    // World offsets per texel along the atlas' x and y: [b - a, e - a] times the inverse of
    // [p1 - p0, p2 - p0] (texels), in the tangents of the normal.
    float2 u1 = p[1] - p[0], u2 = p[2] - p[0];
    float3 dx = ((b - a) * u2.y - (e - a) * u1.y) / area;
    float3 dy = ((e - a) * u1.x - (b - a) * u2.x) / area;
    float3 t1, t2;
    surface_tangents(unit, &t1, &t2);
    axes_out[texel] = (float4)(dot3(dx, t1), dot3(dx, t2), dot3(dy, t1), dot3(dy, t2));
    chart_out[texel] = (float)chart_of[t];
  }
}

// Which 4-neighbours of texel (x, y) lie in its tile `t` (atlas_tile_at): left, right, up, down.
inline int4 atlas_same_tile(uint4 t, uint x, uint y) {
  return (int4)(t.w && x > t.x, t.w && x + 1 < t.x + t.z, t.w && y > t.y, t.w && y + 1 < t.y + t.z);
}

// One step of the gutter's charts: an empty texel (0) takes the lowest chart among its 4-neighbours
// in the same tile (`cells`: atlas_tile_at's), so that each gutter texel extends exactly one chart.
kernel void atlas_dilate_charts(global const float* src, uint texel_count, uint width,
                                global const uint4* cells, uint cell, global float* dst) {
  uint first = get_global_id(0) * TEXEL_CHUNK;
  uint last = min(first + TEXEL_CHUNK, texel_count);
  for (uint texel = first; texel < last; ++texel) {
    float c = src[texel];
    if (c == 0.0f) {
      uint x = texel % width, y = texel / width;
      int4 in = atlas_same_tile(atlas_tile_at(cells, cell, width, x, y), x, y);
      float n[4] = {in.x ? src[texel - 1] : 0.0f, in.y ? src[texel + 1] : 0.0f,
                    in.z ? src[texel - width] : 0.0f, in.w ? src[texel + width] : 0.0f};
      for (int k = 0; k < 4; ++k)
        if (n[k] > 0.0f && (c == 0.0f || n[k] < c)) c = n[k];
    }
    dst[texel] = c;
  }
}

// One step of the gutter: an empty texel (NaN) takes the mean of its non-empty 4-neighbours in
// the same tile that belong to its gutter chart (`charts`: atlas_dilate_charts' result after
// every step, whose layers grow as these do), so a gutter between two charts holds each one's
// own values, never their blend; with fill = 0 a plain copy (no gutter: the atlas leaves the
// pass's buffer).
kernel void atlas_dilate(global const float* src, global const float* charts, uint texel_count,
                         uint width, global const uint4* cells, uint cell, int fill,
                         global float* dst) {
  uint first = get_global_id(0) * TEXEL_CHUNK;
  uint last = min(first + TEXEL_CHUNK, texel_count);
  for (uint texel = first; texel < last; ++texel) {
    float v = src[texel];
    if (!isnan(v) || !fill) {
      dst[texel] = v;
      continue;
    }
    uint x = texel % width, y = texel / width;
    int4 in = atlas_same_tile(atlas_tile_at(cells, cell, width, x, y), x, y);
    float c = charts[texel], sum = 0.0f;
    int n = 0;
    if (in.x && !isnan(src[texel - 1]) && charts[texel - 1] == c) sum += src[texel - 1], ++n;
    if (in.y && !isnan(src[texel + 1]) && charts[texel + 1] == c) sum += src[texel + 1], ++n;
    if (in.z && !isnan(src[texel - width]) && charts[texel - width] == c)
      sum += src[texel - width], ++n;
    if (in.w && !isnan(src[texel + width]) && charts[texel + width] == c)
      sum += src[texel + width], ++n;
    dst[texel] = n > 0 ? sum / n : NAN;
  }
}

// The atlas as two channels for its summed-area table: the visibility at surface texels (0
// elsewhere: empty and gutter texels, which hold no surface point) and the coverage (1 at surface
// texels), so that a box's mean over its surface points is one box sum over the other. `charts`:
// atlas_resolve's chart_out (0 where no surface is).
kernel void atlas_coverage(global const float* atlas, global const float* charts, uint texel_count,
                           global float2* out) {
  uint first = get_global_id(0) * TEXEL_CHUNK;
  uint last = min(first + TEXEL_CHUNK, texel_count);
  for (uint texel = first; texel < last; ++texel) {
    float v = atlas[texel];
    out[texel] = charts[texel] == 0.0f || isnan(v) ? (float2)(0.0f) : (float2)(v, 1.0f);
  }
}

// PRODUCT_ATLAS_UVS: the UV of each corner of triangles [0, triangle_count) of one mesh (its
// first index and vertex in the scene's arrays), a row of three corners per triangle.
kernel void atlas_corner_uvs(global const uint* indices, global const float* uvs, uint index_base,
                             uint vertex_base, uint triangle_count, global float2* out) {
  uint first = get_global_id(0) * TEXEL_CHUNK;
  uint last = min(first + TEXEL_CHUNK, triangle_count);
  for (uint t = first; t < last; ++t)
    for (uint k = 0; k < 3; ++k)
      out[3 * t + k] = vload2(vertex_base + indices[index_base + 3 * t + k], uvs);
}
