// Depth rasterization in five steps, each a kernel sized for a CPU work-item:
//   transform_vertices  clip-space position of every vertex of every draw
//   setup_triangles     homogeneous clipping, snapping to fixed point, depth planes
//   bin_count / bin_scan_tiles / bin_scan_totals / bin_scatter
//                       per-tile triangle lists by counting sort (no atomics, stable order)
//   raster_tiles        one work-item owns one TILE x TILE tile and writes it once
// Coverage is exact: vertices snap to 1/256 pixel and edge functions are evaluated in 64-bit
// integers with the top-left fill rule, so shared edges are neither doubly covered nor holed.
// WRITE_ID additionally keeps the nearest primitive id (ties go to the lower id).

#ifndef TILE
#define TILE 64
#endif
#define VERTEX_CHUNK 64
#define TRIANGLE_CHUNK 64
#define SUBPIXEL 256.0f
#define SUBPIXEL_BITS 8
// The guard band, in viewport widths beyond each side: big enough that clipping against it is
// rare, small enough that snapped coordinates times edge deltas fit in 64 bits (see setup).
#define GUARD 1.0f
#define MAX_POLY 10  // a triangle clipped by 7 planes has at most 3 + 7 vertices

typedef struct {
  int x0, y0, x1, y1, x2, y2;  // snapped vertices, counter-clockwise in the y-down viewport
  float z0, dzdx, dzdy;        // depth plane anchored at the snapped vertex 0, per pixel
  uint prim;                   // primitive id: the draw's out_triangle_base + triangle index
} tri_t;

kernel void transform_vertices(global const float* positions, global const draw_t* draws,
                               uint draw_count, uint vertex_total, global float4* clip) {
  uint first = get_global_id(0) * VERTEX_CHUNK;
  if (first >= vertex_total) return;
  uint last = min(first + VERTEX_CHUNK, vertex_total);
  uint d = find_draw_by_vertex(draws, draw_count, first);
  for (uint o = first; o < last; ++o) {
    while (d + 1 < draw_count && draws[d + 1].out_vertex_base <= o) ++d;
    uint v = draws[d].vertex_base + (o - draws[d].out_vertex_base);
    clip[o] = mul_m4(draws[d].to_clip, (float4)(vload3(v, positions), 1.0f));
  }
}

// Signed distance of a clip-space vertex to clip plane i; inside is >= 0. The viewport is
// x, y in [0, w] (texture space), depth z in [0, w], and w >= a tiny epsilon.
inline float plane_distance(float4 v, int i) {
  switch (i) {
    case 0:
      return v.z;  // near
    case 1:
      return v.w - v.z;  // far
    case 2:
      return v.x + GUARD * v.w;  // left guard band
    case 3:
      return (1.0f + GUARD) * v.w - v.x;
    case 4:
      return v.y + GUARD * v.w;
    case 5:
      return (1.0f + GUARD) * v.w - v.y;
    default:
      return v.w - 1e-6f * fabs(v.z);  // strictly positive w
  }
}

inline uint outcode(float4 v) {
  uint c = 0;
  for (int i = 0; i < 7; ++i) c |= (plane_distance(v, i) < 0.0f) << i;
  return c;
}

// Sutherland-Hodgman against the planes in `mask`; returns the vertex count (0 if culled).
inline int clip_polygon(float4* poly, uint mask) {
  int n = 3;
  float4 tmp[MAX_POLY];
  for (int i = 0; i < 7 && n > 0; ++i) {
    if (!(mask & (1u << i))) continue;
    int m = 0;
    for (int k = 0; k < n; ++k) {
      float4 a = poly[k], b = poly[(k + 1) % n];
      float da = plane_distance(a, i), db = plane_distance(b, i);
      if (da >= 0.0f) tmp[m++] = a;
      if ((da >= 0.0f) != (db >= 0.0f)) tmp[m++] = a + (b - a) * (da / (da - db));
    }
    n = m;
    for (int k = 0; k < n; ++k) poly[k] = tmp[k];
  }
  return n;
}

// How many setup records triangle t produces: 0 (culled), 1, or a clipped fan's size.
inline int load_triangle(global const uint* indices, global const draw_t* draws, uint draw_count,
                         global const float4* clip, uint t, float4* poly, uint* prim) {
  uint d = find_draw_by_triangle(draws, draw_count, t);
  uint local_t = t - draws[d].out_triangle_base;
  global const uint* idx = indices + draws[d].index_base + 3 * local_t;
  uint base = draws[d].out_vertex_base;
  poly[0] = clip[base + idx[0]];
  poly[1] = clip[base + idx[1]];
  poly[2] = clip[base + idx[2]];
  *prim = t;
  uint c0 = outcode(poly[0]), c1 = outcode(poly[1]), c2 = outcode(poly[2]);
  if (c0 & c1 & c2) return 0;
  uint mask = c0 | c1 | c2;
  if (!mask) return 3;
  return clip_polygon(poly, mask);
}

inline tri_t make_record(float4 a, float4 b, float4 c, float vp_w, float vp_h, uint prim) {
  float3 s[3];
  float4 v[3] = {a, b, c};
  int X[3], Y[3];
  for (int k = 0; k < 3; ++k) {
    float inv_w = 1.0f / v[k].w;
    X[k] = convert_int_rte(v[k].x * inv_w * vp_w * SUBPIXEL);
    Y[k] = convert_int_rte(v[k].y * inv_w * vp_h * SUBPIXEL);
    s[k] = (float3)(X[k] / SUBPIXEL, Y[k] / SUBPIXEL, clamp(v[k].z * inv_w, 0.0f, 1.0f));
  }
  long area = (long)(X[1] - X[0]) * (Y[2] - Y[0]) - (long)(X[2] - X[0]) * (Y[1] - Y[0]);
  if (area < 0) {  // make every triangle counter-clockwise so inside means all edges >= 0
    int t = X[1];
    X[1] = X[2];
    X[2] = t;
    t = Y[1];
    Y[1] = Y[2];
    Y[2] = t;
    float3 u = s[1];
    s[1] = s[2];
    s[2] = u;
  }
  tri_t r;
  r.x0 = X[0];
  r.y0 = Y[0];
  r.x1 = X[1];
  r.y1 = Y[1];
  r.x2 = X[2];
  r.y2 = Y[2];
  r.prim = prim;
  r.z0 = s[0].z;
  float dx1 = s[1].x - s[0].x, dy1 = s[1].y - s[0].y, dz1 = s[1].z - s[0].z;
  float dx2 = s[2].x - s[0].x, dy2 = s[2].y - s[0].y, dz2 = s[2].z - s[0].z;
  float det = dx1 * dy2 - dx2 * dy1;
  if (area == 0 || det == 0.0f) {  // degenerate: keep the record but give it no pixels
    r.x1 = r.x2 = r.x0;
    r.y1 = r.y2 = r.y0;
    r.dzdx = r.dzdy = 0.0f;
  } else {
    r.dzdx = (dz1 * dy2 - dz2 * dy1) / det;
    r.dzdy = (dx1 * dz2 - dx2 * dz1) / det;
  }
  return r;
}

// Work-item = TRIANGLE_CHUNK input triangles. Count first, reserve space with one atomic, then
// write; the records' order is not deterministic, but nothing downstream depends on it.
kernel void setup_triangles(global const uint* indices, global const draw_t* draws, uint draw_count,
                            uint triangle_total, global const float4* clip, float vp_w, float vp_h,
                            uint capacity, global tri_t* out, global uint* out_count) {
  uint first = get_global_id(0) * TRIANGLE_CHUNK;
  if (first >= triangle_total) return;
  uint last = min(first + TRIANGLE_CHUNK, triangle_total);
  float4 poly[MAX_POLY];
  uint prim;
  uint needed = 0;
  for (uint t = first; t < last; ++t) {
    int n = load_triangle(indices, draws, draw_count, clip, t, poly, &prim);
    needed += n >= 3 ? n - 2 : 0;
  }
  if (needed == 0) return;
  uint at = atomic_add(out_count, needed);
  for (uint t = first; t < last; ++t) {
    int n = load_triangle(indices, draws, draw_count, clip, t, poly, &prim);
    for (int k = 1; k + 1 < n; ++k, ++at) {
      if (at < capacity) out[at] = make_record(poly[0], poly[k], poly[k + 1], vp_w, vp_h, prim);
    }
  }
}

// The inclusive pixel range a record can cover, clamped to the viewport. Pixel p's centre is
// at p * 256 + 128 in snapped units.
inline int4 pixel_bounds(global const tri_t* r, uint width, uint height) {
  int min_x = min(r->x0, min(r->x1, r->x2)), max_x = max(r->x0, max(r->x1, r->x2));
  int min_y = min(r->y0, min(r->y1, r->y2)), max_y = max(r->y0, max(r->y1, r->y2));
  int4 b;
  b.x = max((min_x - 128 + 255) >> SUBPIXEL_BITS, 0);
  b.y = max((min_y - 128 + 255) >> SUBPIXEL_BITS, 0);
  b.z = min((max_x - 128) >> SUBPIXEL_BITS, (int)width - 1);
  b.w = min((max_y - 128) >> SUBPIXEL_BITS, (int)height - 1);
  return b;
}

// counts[tile * chunks + c]: how many records of chunk c touch the tile. Work-item c owns
// column c, so no two work-items write the same counter.
kernel void bin_count(global const tri_t* tris, uint tri_count, uint chunk_size, uint chunks,
                      uint tiles_x, uint tiles_y, uint width, uint height, global uint* counts) {
  uint c = get_global_id(0);
  if (c >= chunks) return;
  for (uint t = 0; t < tiles_x * tiles_y; ++t) counts[t * chunks + c] = 0;
  uint last = min((c + 1) * chunk_size, tri_count);
  for (uint i = c * chunk_size; i < last; ++i) {
    int4 b = pixel_bounds(tris + i, width, height);
    if (b.x > b.z || b.y > b.w) continue;
    for (int ty = b.y / TILE; ty <= b.w / TILE; ++ty)
      for (int tx = b.x / TILE; tx <= b.z / TILE; ++tx) counts[(ty * tiles_x + tx) * chunks + c]++;
  }
}

// Work-item = one tile: exclusive scan of its chunk counts in place, total to tile_total.
kernel void bin_scan_tiles(global uint* counts, uint chunks, uint tiles, global uint* tile_total) {
  uint t = get_global_id(0);
  if (t >= tiles) return;
  uint sum = 0;
  for (uint c = 0; c < chunks; ++c) {
    uint n = counts[t * chunks + c];
    counts[t * chunks + c] = sum;
    sum += n;
  }
  tile_total[t] = sum;
}

// One work-item: tile_base[t] = first list entry of tile t; tile_base[tiles] = all entries.
kernel void bin_scan_totals(global const uint* tile_total, uint tiles, global uint* tile_base) {
  if (get_global_id(0) != 0) return;
  uint sum = 0;
  for (uint t = 0; t < tiles; ++t) {
    tile_base[t] = sum;
    sum += tile_total[t];
  }
  tile_base[tiles] = sum;
}

kernel void bin_scatter(global const tri_t* tris, uint tri_count, uint chunk_size, uint chunks,
                        uint tiles_x, uint width, uint height, global uint* cursors,
                        global const uint* tile_base, global uint* lists) {
  uint c = get_global_id(0);
  if (c >= chunks) return;
  uint last = min((c + 1) * chunk_size, tri_count);
  for (uint i = c * chunk_size; i < last; ++i) {
    int4 b = pixel_bounds(tris + i, width, height);
    if (b.x > b.z || b.y > b.w) continue;
    for (int ty = b.y / TILE; ty <= b.w / TILE; ++ty)
      for (int tx = b.x / TILE; tx <= b.z / TILE; ++tx) {
        uint tile = ty * tiles_x + tx;
        lists[tile_base[tile] + cursors[tile * chunks + c]++] = i;
      }
  }
}

// Edge function of a -> b at snapped point p; >= 0 inside for counter-clockwise triangles.
inline long edge(long ax, long ay, long bx, long by, long px, long py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// Top-left rule in the y-down viewport: a top edge runs exactly horizontally to the right, a
// left edge runs upwards. Pixels exactly on other edges belong to the neighbour.
inline long fill_bias(int ax, int ay, int bx, int by) {
  int dy = by - ay, dx = bx - ax;
  return (dy < 0 || (dy == 0 && dx > 0)) ? 0 : -1;
}

__attribute__((reqd_work_group_size(1, 1, 1))) kernel void raster_tiles(
    global const tri_t* tris, global const uint* tile_base, global const uint* lists, uint tiles_x,
    uint width, uint height, global float* depth_out
#ifdef WRITE_ID
    ,
    global uint* id_out
#endif
) {
  uint tile = get_global_id(0);
  int tx0 = (tile % tiles_x) * TILE, ty0 = (tile / tiles_x) * TILE;
  int tw = min(TILE, (int)width - tx0), th = min(TILE, (int)height - ty0);
  if (tw <= 0 || th <= 0) return;
  float depth[TILE * TILE];
#ifdef WRITE_ID
  uint ids[TILE * TILE];
#endif
  for (int i = 0; i < TILE * TILE; ++i) {
    depth[i] = 1.0f;
#ifdef WRITE_ID
    ids[i] = 0xffffffffu;
#endif
  }
  for (uint e = tile_base[tile]; e < tile_base[tile + 1]; ++e) {
    global const tri_t* r = tris + lists[e];
    int4 b = pixel_bounds(r, width, height);
    int x_lo = max(b.x, tx0), x_hi = min(b.z, tx0 + tw - 1);
    int y_lo = max(b.y, ty0), y_hi = min(b.w, ty0 + th - 1);
    if (x_lo > x_hi || y_lo > y_hi) continue;
    long bias0 = fill_bias(r->x1, r->y1, r->x2, r->y2);
    long bias1 = fill_bias(r->x2, r->y2, r->x0, r->y0);
    long bias2 = fill_bias(r->x0, r->y0, r->x1, r->y1);
    // Per-pixel steps of the three edge functions.
    long sx0 = -(long)(r->y2 - r->y1) << SUBPIXEL_BITS, sy0 = (long)(r->x2 - r->x1)
                                                              << SUBPIXEL_BITS;
    long sx1 = -(long)(r->y0 - r->y2) << SUBPIXEL_BITS, sy1 = (long)(r->x0 - r->x2)
                                                              << SUBPIXEL_BITS;
    long sx2 = -(long)(r->y1 - r->y0) << SUBPIXEL_BITS, sy2 = (long)(r->x1 - r->x0)
                                                              << SUBPIXEL_BITS;
    long px = ((long)x_lo << SUBPIXEL_BITS) + 128, py = ((long)y_lo << SUBPIXEL_BITS) + 128;
    long e0 = edge(r->x1, r->y1, r->x2, r->y2, px, py) + bias0;
    long e1 = edge(r->x2, r->y2, r->x0, r->y0, px, py) + bias1;
    long e2 = edge(r->x0, r->y0, r->x1, r->y1, px, py) + bias2;
    float fx0 = r->x0 / SUBPIXEL, fy0 = r->y0 / SUBPIXEL;
    for (int y = y_lo; y <= y_hi; ++y, e0 += sy0, e1 += sy1, e2 += sy2) {
      float zrow = r->z0 + r->dzdy * ((float)y + 0.5f - fy0);
      int row = (y - ty0) * TILE - tx0;
      for (int x = x_lo; x <= x_hi; ++x) {
        long k = x - x_lo;
        if ((e0 + k * sx0) < 0 || (e1 + k * sx1) < 0 || (e2 + k * sx2) < 0) continue;
        float z = clamp(zrow + r->dzdx * ((float)x + 0.5f - fx0), 0.0f, 1.0f);
#ifdef WRITE_ID
        if (z < depth[row + x] || (z == depth[row + x] && r->prim < ids[row + x])) {
          depth[row + x] = z;
          ids[row + x] = r->prim;
        }
#else
        depth[row + x] = fmin(depth[row + x], z);
#endif
      }
    }
  }
  for (int y = 0; y < th; ++y)
    for (int x = 0; x < tw; ++x) {
      size_t o = (size_t)(ty0 + y) * width + (tx0 + x);
      depth_out[o] = depth[y * TILE + x];
#ifdef WRITE_ID
      id_out[o] = ids[y * TILE + x];
#endif
    }
}
