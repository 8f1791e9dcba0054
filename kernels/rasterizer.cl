// Depth rasterization in five steps, each a kernel sized for a CPU work-item:
//   transform_vertices  clip-space position of every vertex of every draw (optionally biased)
//   setup_triangles     homogeneous clipping, snapping to fixed point, depth planes, bounds
//   bin_count / bin_scan_tiles / bin_scan_totals / bin_scatter
//                       per-tile copies of the records by counting sort (no atomics, stable)
//   raster_tiles        one work-item owns one TILE x TILE tile and writes it once
// raster_load sums what the raster's time grows with over the set-up's records at several map
// sizes, without binning or rasterizing (binning counts it at its own size).
// Coverage is exact: vertices snap to 1/256 pixel and edge functions are evaluated in 64-bit
// integers with the top-left fill rule, so shared edges are neither doubly covered nor holed.
// The bins hold copies, not indices: a tile then streams its records instead of paying a cache
// miss per triangle. WRITE_ID also keeps the nearest primitive id (ties go to the lower id).

// ---- Both shapes: the same operations in the same order, so the same bits ----

#ifndef TILE
#define TILE 64
#endif
#define SUBPIXEL 256.0f
#define SUBPIXEL_BITS 8

typedef struct {
  int x0, y0, x1, y1, x2, y2;         // snapped vertices, counter-clockwise in the y-down viewport
  float z0, dzdx, dzdy;               // depth plane anchored at the snapped vertex 0, per pixel
  uint prim;                          // primitive id: the draw's out_triangle_base + triangle index
  ushort min_x, min_y, max_x, max_y;  // pixels whose centres it may cover; empty if min > max
} tri_t;

// The records setup_triangles wrote: a slot per input triangle (`triangle_total`), then the
// clipped ones' extra fan triangles, counted in `extra`, those past `capacity` left unwritten.
// The consumers read the count here rather than the host between the launches: the host reads
// the records wanted (records_wanted) with the binning's totals, and sets up again with room
// for them when they did not fit (rare: clipping makes few).
inline uint record_count(uint triangle_total, uint capacity, global const uint* extra) {
  return (uint)min((ulong)triangle_total + extra[0], (ulong)capacity);
}
inline ulong records_wanted(uint triangle_total, global const uint* extra) {
  return (ulong)triangle_total + extra[0];
}

// A record's box (the pixels whose centres it may cover; none if min > max) with its pixels
// shifted down `shift` bits, as at a map whose edge is halved that often: its pixels and the
// tiles it overlaps.
inline bool box_empty(global const tri_t* r) {
  return r->min_x > r->max_x || r->min_y > r->max_y;
}
inline ulong box_pixels(global const tri_t* r, uint shift) {
  return (ulong)((r->max_x >> shift) - (r->min_x >> shift) + 1) *
         ((r->max_y >> shift) - (r->min_y >> shift) + 1);
}
inline ulong box_tiles(global const tri_t* r, uint shift) {
  return (ulong)(((r->max_x >> shift) / TILE) - ((r->min_x >> shift) / TILE) + 1) *
         (((r->max_y >> shift) / TILE) - ((r->min_y >> shift) / TILE) + 1);
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

// Whether the triangle (x0, y0), (x1, y1), (x2, y2) covers the centre of pixel (x, y): 64-bit
// edge functions, top-left rule.
inline bool covers_centre(int x0, int y0, int x1, int y1, int x2, int y2, int x, int y) {
  long px = ((long)x << SUBPIXEL_BITS) + 128, py = ((long)y << SUBPIXEL_BITS) + 128;
  long e0 = edge(x1, y1, x2, y2, px, py) + fill_bias(x1, y1, x2, y2);
  long e1 = edge(x2, y2, x0, y0, px, py) + fill_bias(x2, y2, x0, y0);
  long e2 = edge(x0, y0, x1, y1, px, py) + fill_bias(x0, y0, x1, y1);
  return (e0 | e1 | e2) >= 0;
}

// The depth of a record's plane (z0, dzdx, dzdy anchored at fx0, fy0) at pixel (x, y): every
// path of both shapes evaluates it with these same expressions, so they write the same bits.
inline float plane_row(float z0, float dzdy, float fy0, int y) {
  return z0 + dzdy * ((float)y + 0.5f - fy0);
}
inline float plane_at(float zrow, float dzdx, float fx0, int x) {
  return clamp(zrow + dzdx * ((float)x + 0.5f - fx0), 0.0f, 1.0f);
}

// Hierarchical z: whether the plane lies behind `far` (a bound on every texel's depth) over the
// whole box [x_lo, x_hi] x [y_lo, y_hi], so that the record can win none of its texels. The
// plane's least value over the box is at a corner. Each of the few float operations of plane_at
// rounds by at most 2^-24 of the magnitudes involved: 2^-20 of their sum bounds the total, so no
// texel the record could win is skipped.
inline bool plane_behind(float z0, float dzdx, float dzdy, float fx0, float fy0, int x_lo, int x_hi,
                         int y_lo, int y_hi, float far) {
  float ax = dzdx * ((float)x_lo + 0.5f - fx0), bx = dzdx * ((float)x_hi + 0.5f - fx0);
  float ay = dzdy * ((float)y_lo + 0.5f - fy0), by = dzdy * ((float)y_hi + 0.5f - fy0);
  float zmin = z0 + fmin(ax, bx) + fmin(ay, by);
  float slack = 0x1p-20f * (1.0f + fabs(z0) + fmax(fabs(ax), fabs(bx)) + fmax(fabs(ay), fabs(by)));
#ifdef WRITE_ID
  return zmin - slack > far;  // an equal depth may still win on its lower id
#else
  return zmin - slack >= far;
#endif
}

// Depth test and write of one texel of the arrays `depth` (and `ids`) in scope; `in` = the pixel
// centre is covered. The nearest depth wins, and among equal depths the lower id: the result does
// not depend on the order records arrive in.
#ifdef WRITE_ID
#define DEPTH_WRITE(i, in, z, prim)                                \
  {                                                                \
    float d_ = depth[i];                                           \
    uint id_ = ids[i];                                             \
    bool win_ = (in) && ((z) < d_ || ((z) == d_ && (prim) < id_)); \
    depth[i] = win_ ? (z) : d_;                                    \
    ids[i] = win_ ? (prim) : id_;                                  \
  }
#else
#define DEPTH_WRITE(i, in, z, prim)     \
  {                                     \
    float d_ = depth[i];                \
    depth[i] = (in) ? fmin(d_, z) : d_; \
  }
#endif

// Virtual maps (issue 53), built with -DPAGED: the map is a virtual level's window, and a TILE x
// TILE tile is binned only where its PAGE_TEXELS^2 page has a slot in `page_table` (a slot or
// NO_PAGE per page, row-major from `page_first`). The raster's work runs over the level's pages to
// draw alone (`draws`: slot and page, from `draw_first`), and a tile's texels go to its slot of the
// pool, row-major within the page. Each texel is the same expression as on a dense map of the
// window, so a page equals the dense map's texels bit for bit. Dense maps ignore these arguments.
#define PAGE_TEXELS 128
#define NO_PAGE 0xffffffffu
inline uint tile_slot(global const uint* page_table, uint page_first, uint tiles_x, uint tile) {
#ifdef PAGED
  uint per_page = PAGE_TEXELS / TILE, tx = tile % tiles_x, ty = tile / tiles_x;
  return page_table[page_first + (ty / per_page) * (tiles_x / per_page) + tx / per_page];
#else
  return 0;
#endif
}
inline bool tile_drawn(global const uint* page_table, uint page_first, uint tiles_x, uint tile) {
  return tile_slot(page_table, page_first, tiles_x, tile) != NO_PAGE;
}
// The raster's work-item `item` (a tile, or a work-group's tile): the map's tile, or (PAGED) the
// tile (item % 4) of draws[draw_first + item / 4]'s page; *slot is its slot.
inline uint raster_tile(uint item, global const uint2* draws, uint draw_first, uint tiles_x,
                        uint* slot) {
#ifdef PAGED
  uint per_page = PAGE_TEXELS / TILE, quarter = per_page * per_page;
  uint2 draw = draws[draw_first + item / quarter];
  *slot = draw.x;
  uint page = draw.y, pages = tiles_x / per_page, q = item % quarter;
  return ((page / pages) * per_page + q / per_page) * tiles_x + (page % pages) * per_page +
         q % per_page;
#else
  *slot = 0;
  return item;
#endif
}
// Where texel (x, y) of the map is stored: row-major in the map, or within its page's slot.
inline size_t texel_index(uint slot, int x, int y, uint width) {
#ifdef PAGED
  return (size_t)slot * (PAGE_TEXELS * PAGE_TEXELS) + (size_t)(y % PAGE_TEXELS) * PAGE_TEXELS +
         x % PAGE_TEXELS;
#else
  return (size_t)y * width + x;
#endif
}
#define DRAWN(tile) tile_drawn(page_table, page_first, tiles_x, tile)
// The tiles (tx, ty) of record r's box that binning visits: those inside `rect` (x0, y0, x1, y1
// in tiles, inclusive): the level's pages' bounding box, or everything for a dense map.
#define FOR_BOX_TILES(r, tx, ty)                                                        \
  for (int ty = max(r->min_y / TILE, rect.y); ty <= min(r->max_y / TILE, rect.w); ++ty) \
    for (int tx = max(r->min_x / TILE, rect.x); tx <= min(r->max_x / TILE, rect.z); ++tx)

// ---- CPU shape ----

#ifndef VERTEX_CHUNK
#define VERTEX_CHUNK 1024
#endif
#ifndef TRIANGLE_CHUNK
#define TRIANGLE_CHUNK 256
#endif
// The guard band, in viewport widths beyond each side: big enough that clipping against it is
// rare, small enough that snapped coordinates times edge deltas fit in 64 bits (see setup).
#define GUARD 1.0f
#define MAX_POLY 10  // a triangle clipped by 7 planes has at most 3 + 7 vertices

// hypot() spelled out (OpenCL lets it be off by 4 ulp, each device its own way): scaled by a
// power of two, exactly, so that the squares neither overflow nor underflow.
inline float hypot2(float x, float y) {
  float m = fmax(fabs(x), fabs(y));
  if (m == 0.0f || isinf(m)) return m;
  int e;
  frexp(m, &e);
  float xs = ldexp(x, -e), ys = ldexp(y, -e);
  return ldexp(sqrt(fma(xs, xs, ys * ys)), e);
}

// The world size of one shadow-map texel at world point p across the unit light direction l:
// on the plane through p perpendicular to l, J maps a world step to map NDC (0..1); the longest
// world step that one texel (1/map_size) can be is the larger singular value of J^-1 over
// map_size. 0 where J is singular (p on the light's axis line through its centre of projection).
inline float world_texel_size(float16 m, float3 p, float3 l, float inv_map_size) {
  float3 t1 =
      normalize3(fabs(l.x) < 0.9f ? cross3(l, (float3)(1, 0, 0)) : cross3(l, (float3)(0, 1, 0)));
  float3 t2 = cross3(l, t1);
  float4 c = mul_m4(m, (float4)(p, 1.0f));
  float4 m1 = mul_m4(m, (float4)(t1, 0.0f)), m2 = mul_m4(m, (float4)(t2, 0.0f));
  float2 ndc = c.xy / c.w;
  float2 j1 = (m1.xy - ndc * m1.w) / c.w, j2 = (m2.xy - ndc * m2.w) / c.w;
  float det = j1.x * j2.y - j2.x * j1.y;
  if (det == 0.0f || !isfinite(det)) return 0.0f;
  // J^-1 = [j2.y, -j2.x; -j1.y, j1.x] / det, columns a1, a2; larger singular value as in
  // texel_density.cl.
  float2 a1 = (float2)(j2.y, -j1.y) / det, a2 = (float2)(-j2.x, j1.x) / det;
  float s = 0.5f * (hypot2(a1.x + a2.y, a1.y - a2.x) + hypot2(a1.x - a2.y, a1.y + a2.x));
  return isfinite(s) ? s * inv_map_size : 0.0f;
}

// Clip-space position of every vertex of every draw. With a world-space bias (a light's map,
// Kozlov 14.3.1; bias_a = bias_b = 0 otherwise, the camera view always) each vertex moves first:
// P_biased = P + L (a + b texel(P)), L the unit direction of the light's travel at P (away from
// the light), then clip = world_to_ndc P_biased: along the light's axis for a directional light,
// from its position for a spot or point light.
kernel void transform_vertices(global const float* positions, global const draw_t* draws,
                               uint draw_count, uint vertex_total, global float4* clip,
                               float16 world_to_ndc, light_t light, float bias_a, float bias_b,
                               float inv_map_size) {
  uint first = get_global_id(0) * VERTEX_CHUNK;
  if (first >= vertex_total) return;
  uint last = min(first + VERTEX_CHUNK, vertex_total);
  uint d = find_draw(draws, draw_count, first, 0);
  bool biased = bias_a != 0.0f || bias_b != 0.0f;
  for (uint o = first; o < last; ++o) {
    while (d + 1 < draw_count && draws[d + 1].out_vertex_base <= o) ++d;
    uint v = draws[d].vertex_base + (o - draws[d].out_vertex_base);
    float4 object = (float4)(vload3(v, positions), 1.0f);
    if (!biased) {
      clip[o] = mul_m4(draws[d].to_clip, object);
      continue;
    }
    float3 p = mul_m4(draws[d].to_world, object).xyz;
    float3 l =
        light.kind == LIGHT_DIRECTIONAL ? light.axis.xyz : normalize3(p - light.position.xyz);
    float offset = bias_a;
    if (bias_b != 0.0f) offset += bias_b * world_texel_size(world_to_ndc, p, l, inv_map_size);
    clip[o] = mul_m4(world_to_ndc, (float4)(p + offset * l, 1.0f));
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

// Bit i set: outside plane i. Spelled out (same expressions as plane_distance) so that it
// compiles to straight-line code: it runs for every triangle.
// Scalar arguments: setup_run's loop vectorizes only without OpenCL vector values.
inline uint outcode_xyzw(float x, float y, float z, float w) {
  const float g = GUARD * w, h = (1.0f + GUARD) * w;
  return (uint)(z < 0.0f) | (uint)(w - z < 0.0f) << 1 | (uint)(x + g < 0.0f) << 2 |
         (uint)(h - x < 0.0f) << 3 | (uint)(y + g < 0.0f) << 4 | (uint)(h - y < 0.0f) << 5 |
         (uint)(w - 1e-6f * fabs(z) < 0.0f) << 6;
}
inline uint outcode(float4 v) {
  return outcode_xyzw(v.x, v.y, v.z, v.w);
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
      // Interpolate from the inside end, so that the two triangles sharing an edge compute the
      // very same point and no crack opens along a clipped shared edge.
      if (da >= 0.0f && db < 0.0f) tmp[m++] = a + (b - a) * (da / (da - db));
      if (da < 0.0f && db >= 0.0f) tmp[m++] = b + (a - b) * (db / (db - da));
    }
    n = m;
    for (int k = 0; k < n; ++k) poly[k] = tmp[k];
  }
  return n;
}

// Loads triangle t of draw d and clips it; returns the polygon's vertex count (< 3: culled).
inline int load_triangle(global const uint* indices, global const draw_t* draws, uint d,
                         global const float4* clip, uint t, float4* poly) {
  uint local_t = t - draws[d].out_triangle_base;
  global const uint* idx = indices + draws[d].index_base + 3 * local_t;
  uint base = draws[d].out_vertex_base;
  poly[0] = clip[base + idx[0]];
  poly[1] = clip[base + idx[1]];
  poly[2] = clip[base + idx[2]];
  uint c0 = outcode(poly[0]), c1 = outcode(poly[1]), c2 = outcode(poly[2]);
  if (c0 & c1 & c2) return 0;
  uint mask = c0 | c1 | c2;
  if (!mask) return 3;
  return clip_polygon(poly, mask);
}

// The inclusive range of pixels whose centres (p * 256 + 128 in snapped units) may be covered.
inline void write_bounds(global tri_t* r, int2 p0, int2 p1, int2 p2, float vp_w, float vp_h) {
  int2 lo = min(p0, min(p1, p2)), hi = max(p0, max(p1, p2));
  int x0 = max((lo.x - 128 + 255) >> SUBPIXEL_BITS, 0);
  int y0 = max((lo.y - 128 + 255) >> SUBPIXEL_BITS, 0);
  int x1 = min((hi.x - 128) >> SUBPIXEL_BITS, (int)vp_w - 1);
  int y1 = min((hi.y - 128) >> SUBPIXEL_BITS, (int)vp_h - 1);
  if (x0 > x1 || y0 > y1) x0 = y0 = 1, x1 = y1 = 0;  // covers no pixel centre
  r->min_x = x0, r->min_y = y0, r->max_x = x1, r->max_y = y1;
}

inline void write_dead_record(global tri_t* r, uint prim) {
  r->prim = prim;
  r->min_x = r->min_y = 1;
  r->max_x = r->max_y = 0;
}

// A clip-space vertex on the viewport's 1/256-pixel grid; inv_w = 1 / v.w.
inline int2 snap(float4 v, float inv_w, float vp_w, float vp_h) {
  return convert_int2_rte((float2)(v.x * vp_w, v.y * vp_h) * (SUBPIXEL * inv_w));
}

inline void write_record(global tri_t* r, float4 a, float4 b, float4 c, float vp_w, float vp_h,
                         uint prim) {
  const float3 inv_w = 1.0f / (float3)(a.w, b.w, c.w);
  int2 p0 = snap(a, inv_w.x, vp_w, vp_h), p1 = snap(b, inv_w.y, vp_w, vp_h),
       p2 = snap(c, inv_w.z, vp_w, vp_h);
  float z0 = clamp(a.z * inv_w.x, 0.0f, 1.0f), z1 = clamp(b.z * inv_w.y, 0.0f, 1.0f),
        z2 = clamp(c.z * inv_w.z, 0.0f, 1.0f);
  long area = (long)(p1.x - p0.x) * (p2.y - p0.y) - (long)(p2.x - p0.x) * (p1.y - p0.y);
  if (area == 0) {
    write_dead_record(r, prim);
    return;
  }
  if (area < 0) {  // make every triangle counter-clockwise so inside means all edges >= 0
    int2 tp = p1;
    p1 = p2;
    p2 = tp;
    float tz = z1;
    z1 = z2;
    z2 = tz;
  }
  // The depth plane through the snapped vertices, per pixel; 1/det from the exact area.
  float2 d1 = convert_float2(p1 - p0) / SUBPIXEL, d2 = convert_float2(p2 - p0) / SUBPIXEL;
  float inv_det = (SUBPIXEL * SUBPIXEL) / (float)(area < 0 ? -area : area);
  r->x0 = p0.x, r->y0 = p0.y, r->x1 = p1.x, r->y1 = p1.y, r->x2 = p2.x, r->y2 = p2.y;
  r->z0 = z0;
  r->dzdx = ((z1 - z0) * d2.y - (z2 - z0) * d1.y) * inv_det;
  r->dzdy = (d1.x * (z2 - z0) - d2.x * (z1 - z0)) * inv_det;
  r->prim = prim;
  write_bounds(r, p0, p1, p2, vp_w, vp_h);
}

#ifndef VECTOR_SETUP
#define VECTOR_SETUP 1
#endif

// write_record for a run of triangles [t0, t0 + n) as straight-line scalar code, so that the loop
// vectorizes across triangles (float4 values and branches stop LLVM's loop vectorizer): the same
// expressions as write_record, so the records are bit-identical. A triangle that any plane
// clips or culls is only flagged in `clipped` (its slot gets a record of stand-in values) and
// left to the scalar path.
// The vectorized loop reads and writes private arrays field by field (unit-stride vector loads
// and stores); scalar loops fill them from the vertices and copy the records out. Inside the
// vectorized loop, the vertex loads were 12 gathers and the 12-word records 12 scatters a
// triangle: set-up took ~13 ms for the 10^6-triangle crowd at 2048², ~9 ms now
// (docs/benchmarks.md). The run spans draws (the scalar loop follows them, from draw d on):
// one run per draw left the vector loop a few lanes wide on scenes of many small instances.
inline void setup_run(global const uint* restrict indices, global const draw_t* draws,
                      uint draw_count, uint d, global const float* restrict clip, uint t0, uint n,
                      float vp_w, float vp_h, global uint* restrict out, uchar* clipped) {
#define S TRIANGLE_CHUNK
  float v[12 * S];      // the run's clip-space vertices: x y z w of a, then of b, then of c
  uint staged[12 * S];  // its records field by field (tri_t as 12 words)
#pragma clang loop vectorize(disable)
  for (uint k = 0; k < n; ++k) {
    while (d + 1 < draw_count && draws[d + 1].out_triangle_base <= t0 + k) ++d;
    global const uint* idx =
        indices + draws[d].index_base + 3 * (t0 + k - draws[d].out_triangle_base);
    uint vbase = draws[d].out_vertex_base;
    for (int j = 0; j < 3; ++j) {
      float4 c = vload4(vbase + idx[j], clip);
      v[(4 * j) * S + k] = c.x, v[(4 * j + 1) * S + k] = c.y;
      v[(4 * j + 2) * S + k] = c.z, v[(4 * j + 3) * S + k] = c.w;
    }
  }
  for (uint k = 0; k < n; ++k) {
    float ax = v[k], ay = v[S + k], az = v[2 * S + k], aw = v[3 * S + k];
    float bx = v[4 * S + k], by = v[5 * S + k], bz = v[6 * S + k], bw = v[7 * S + k];
    float cx = v[8 * S + k], cy = v[9 * S + k], cz = v[10 * S + k], cw = v[11 * S + k];
    uint mask =
        outcode_xyzw(ax, ay, az, aw) | outcode_xyzw(bx, by, bz, bw) | outcode_xyzw(cx, cy, cz, cw);
    clipped[k] = mask != 0;
    aw = mask ? 1.0f : aw, bw = mask ? 1.0f : bw, cw = mask ? 1.0f : cw;
    float ia = 1.0f / aw, ib = 1.0f / bw, ic = 1.0f / cw;
    int p0x = (int)rint((ax * vp_w) * (SUBPIXEL * ia));
    int p0y = (int)rint((ay * vp_h) * (SUBPIXEL * ia));
    int p1x = (int)rint((bx * vp_w) * (SUBPIXEL * ib));
    int p1y = (int)rint((by * vp_h) * (SUBPIXEL * ib));
    int p2x = (int)rint((cx * vp_w) * (SUBPIXEL * ic));
    int p2y = (int)rint((cy * vp_h) * (SUBPIXEL * ic));
    p0x = mask ? 0 : p0x, p0y = mask ? 0 : p0y, p1x = mask ? 0 : p1x;
    p1y = mask ? 0 : p1y, p2x = mask ? 0 : p2x, p2y = mask ? 0 : p2y;
    // clamp() and convert_int_rte() spelled as fmin(fmax()) and rint(): the same values, but
    // vectorizable.
    float z0 = fmin(fmax(az * ia, 0.0f), 1.0f), z1 = fmin(fmax(bz * ib, 0.0f), 1.0f),
          z2 = fmin(fmax(cz * ic, 0.0f), 1.0f);
    long area = (long)(p1x - p0x) * (p2y - p0y) - (long)(p2x - p0x) * (p1y - p0y);
    bool flip = area < 0;
    int qx = flip ? p2x : p1x, qy = flip ? p2y : p1y, rx = flip ? p1x : p2x, ry = flip ? p1y : p2y;
    float zq = flip ? z2 : z1, zr = flip ? z1 : z2;
    float d1x = (float)(qx - p0x) / SUBPIXEL, d1y = (float)(qy - p0y) / SUBPIXEL;
    float d2x = (float)(rx - p0x) / SUBPIXEL, d2y = (float)(ry - p0y) / SUBPIXEL;
    float inv_det = (SUBPIXEL * SUBPIXEL) / (float)(area < 0 ? -area : area);
    float dzdx = ((zq - z0) * d2y - (zr - z0) * d1y) * inv_det;
    float dzdy = (d1x * (zr - z0) - d2x * (zq - z0)) * inv_det;
    int lox = min(p0x, min(qx, rx)), loy = min(p0y, min(qy, ry));
    int hix = max(p0x, max(qx, rx)), hiy = max(p0y, max(qy, ry));
    int bx0 = max((lox - 128 + 255) >> SUBPIXEL_BITS, 0);
    int by0 = max((loy - 128 + 255) >> SUBPIXEL_BITS, 0);
    int bx1 = min((hix - 128) >> SUBPIXEL_BITS, (int)vp_w - 1);
    int by1 = min((hiy - 128) >> SUBPIXEL_BITS, (int)vp_h - 1);
    bool empty = bx0 > bx1 || by0 > by1 || area == 0;
    bx0 = empty ? 1 : bx0, by0 = empty ? 1 : by0, bx1 = empty ? 0 : bx1, by1 = empty ? 0 : by1;
    // tri_t as 12 words: x0 y0 x1 y1 x2 y2 z0 dzdx dzdy prim (min_x min_y) (max_x max_y).
    uint* w = staged + k;
    w[0] = (uint)p0x, w[S] = (uint)p0y, w[2 * S] = (uint)qx, w[3 * S] = (uint)qy;
    w[4 * S] = (uint)rx, w[5 * S] = (uint)ry, w[6 * S] = as_uint(z0), w[7 * S] = as_uint(dzdx);
    w[8 * S] = as_uint(dzdy), w[9 * S] = t0 + k;
    w[10 * S] = (uint)bx0 | (uint)by0 << 16, w[11 * S] = (uint)bx1 | (uint)by1 << 16;
  }
#pragma clang loop vectorize(disable)
  for (uint k = 0; k < n; ++k) {
    global uint* w = out + 12 * (size_t)(t0 + k);
#pragma unroll
    for (int j = 0; j < 12; ++j) w[j] = staged[j * S + k];
  }
#undef S
}

// Work-item = TRIANGLE_CHUNK input triangles. Triangle t's record goes to slot t (a dead
// record if culled); the extra fan triangles of clipped ones, which are rare, are appended
// after triangle_total with an atomic counter.
kernel void setup_triangles(global const uint* indices, global const draw_t* draws, uint draw_count,
                            uint triangle_total, global const float4* clip, float vp_w, float vp_h,
                            uint capacity, global tri_t* out, global uint* extra_count) {
  uint first = get_global_id(0) * TRIANGLE_CHUNK;
  if (first >= triangle_total) return;
  uint last = min(first + TRIANGLE_CHUNK, triangle_total);
  uint d = find_draw(draws, draw_count, first, 1);
  float4 poly[MAX_POLY];
#if VECTOR_SETUP
  uchar clipped[TRIANGLE_CHUNK];
  setup_run(indices, draws, draw_count, d, (global const float*)clip, first, last - first, vp_w,
            vp_h, (global uint*)out, clipped);
#endif
  for (uint t = first; t < last; ++t) {
#if VECTOR_SETUP
    if (!clipped[t - first]) continue;
#endif
    while (d + 1 < draw_count && draws[d + 1].out_triangle_base <= t) ++d;
    int n = load_triangle(indices, draws, d, clip, t, poly);
    if (n < 3) {
      write_dead_record(out + t, t);
      continue;
    }
    write_record(out + t, poly[0], poly[1], poly[2], vp_w, vp_h, t);
    for (int k = 2; k + 1 < n; ++k) {
      uint at = triangle_total + atomic_inc(extra_count);
      if (at < capacity) write_record(out + at, poly[0], poly[k], poly[k + 1], vp_w, vp_h, t);
    }
  }
}

#ifndef BIN_BY_CHUNK
#define BIN_BY_CHUNK 1
#endif
#define SCAN_TILES 64
// The tile x chunk counter matrix. BIN_BY_CHUNK: each chunk's counters are contiguous, so the
// counting and scattering work-items (one per chunk) touch their own block instead of one
// counter every `chunks` words (a cache miss per record at 8192^2); the scan then runs over
// rows of SCAN_TILES tiles. Otherwise each tile's counters are contiguous.
#if BIN_BY_CHUNK
#define COUNTER(tile, c) counts[(size_t)(c)*tiles + (tile)]
#else
#define COUNTER(tile, c) counts[(size_t)(tile)*chunks + (c)]
#endif

// COUNTER(tile, c): how many records of chunk c touch the tile. Work-item c owns chunk c's
// counters, so no two work-items write the same counter. chunk_pixels[c]: the pixels of chunk c's
// records' boxes (the raster's load, with the overlaps; raster_load).
kernel void bin_count(global const tri_t* tris, uint triangle_total, uint capacity,
                      global const uint* extra, uint chunk_size, uint chunks, uint tiles_x,
                      uint tiles_y, global uint* counts, global ulong* chunk_pixels,
                      global const uint* page_table, uint page_first, int4 rect) {
  uint c = get_global_id(0);
  if (c >= chunks) return;
  uint tri_count = record_count(triangle_total, capacity, extra);
  uint tiles = tiles_x * tiles_y;
  for (uint t = 0; t < tiles; ++t) COUNTER(t, c) = 0;
  ulong pixels = 0;
  uint last = min((c + 1) * chunk_size, tri_count);
  for (uint i = c * chunk_size; i < last; ++i) {
    global const tri_t* r = tris + i;
    if (box_empty(r)) continue;
    pixels += box_pixels(r, 0);
    FOR_BOX_TILES(r, tx, ty)
    if (DRAWN(ty * tiles_x + tx)) COUNTER(ty * tiles_x + tx, c)++;
  }
  chunk_pixels[c] = pixels;
}

// Exclusive scan of each tile's chunk counts in place, its total to tile_total. Work-item =
// SCAN_TILES tiles (BIN_BY_CHUNK) or one tile.
kernel void bin_scan_tiles(global uint* counts, uint chunks, uint tiles, global uint* tile_total) {
#if BIN_BY_CHUNK
  uint t0 = get_global_id(0) * SCAN_TILES;
  if (t0 >= tiles) return;
  uint n = min((uint)SCAN_TILES, tiles - t0);
  uint sum[SCAN_TILES];
  for (uint i = 0; i < SCAN_TILES; ++i) sum[i] = 0;
  for (uint c = 0; c < chunks; ++c) {
    global uint* row = counts + (size_t)c * tiles + t0;
    for (uint i = 0; i < n; ++i) {
      uint v = row[i];
      row[i] = sum[i];
      sum[i] += v;
    }
  }
  for (uint i = 0; i < n; ++i) tile_total[t0 + i] = sum[i];
#else
  uint t = get_global_id(0);
  if (t >= tiles) return;
  uint sum = 0;
  for (uint c = 0; c < chunks; ++c) {
    uint n = COUNTER(t, c);
    COUNTER(t, c) = sum;
    sum += n;
  }
  tile_total[t] = sum;
#endif
}

// One work-item: tile_base[t] = first list entry of tile t; tile_base[tiles] = all entries (the
// overlaps), tile_base[tiles + 1] = all box pixels, tile_base[tiles + 2] = the records set-up
// wanted (records_wanted), which the host reads with them. 64-bit, so that the host can refuse
// (not wrap) a scene whose bins would not fit.
kernel void bin_scan_totals(global const uint* tile_total, uint tiles,
                            global const ulong* chunk_pixels, uint chunks, uint triangle_total,
                            global const uint* extra, global ulong* tile_base) {
  if (get_global_id(0) != 0) return;
  ulong sum = 0;
  for (uint t = 0; t < tiles; ++t) {
    tile_base[t] = sum;
    sum += tile_total[t];
  }
  tile_base[tiles] = sum;
  ulong pixels = 0;
  for (uint c = 0; c < chunks; ++c) pixels += chunk_pixels[c];
  tile_base[tiles + 1] = pixels;
  tile_base[tiles + 2] = records_wanted(triangle_total, extra);
}

#define MAX_LOAD_LEVELS 4
// The raster's load (Rasterizer::load): per chunk of records, at the viewport they were set up
// for (level 0) and at each whose edge is halved `level` times, the triangle-tile overlaps that
// binning makes and the pixels of the records' boxes, which raster_tiles visits once per tile.
// At a coarser level a box's pixels are its level-0 pixels shifted down. Level 0 is exactly what
// binning counts. load[(c * levels + level) * 2 + 0 / 1]: overlaps / pixels; after them, the
// records set-up wanted (records_wanted).
kernel void raster_load(global const tri_t* tris, uint triangle_total, uint capacity,
                        global const uint* extra, uint chunk_size, uint chunks, uint levels,
                        global ulong* load) {
  uint c = get_global_id(0);
  if (c >= chunks) return;
  uint tri_count = record_count(triangle_total, capacity, extra);
  if (c == 0) load[(size_t)chunks * levels * 2] = records_wanted(triangle_total, extra);
  ulong overlaps[MAX_LOAD_LEVELS] = {0}, pixels[MAX_LOAD_LEVELS] = {0};
  uint last = min((c + 1) * chunk_size, tri_count);
  for (uint i = c * chunk_size; i < last; ++i) {
    global const tri_t* r = tris + i;
    if (box_empty(r)) continue;  // no pixel centre, no tile
    for (uint k = 0; k < levels; ++k) {
      overlaps[k] += box_tiles(r, k);
      pixels[k] += box_pixels(r, k);
    }
  }
  for (uint k = 0; k < levels; ++k) {
    load[((size_t)c * levels + k) * 2] = overlaps[k];
    load[((size_t)c * levels + k) * 2 + 1] = pixels[k];
  }
}

kernel void bin_scatter(global const tri_t* tris, uint triangle_total, uint capacity,
                        global const uint* extra, uint chunk_size, uint chunks, uint tiles_x,
                        uint tiles_y, global uint* counts, global const ulong* tile_base,
                        global tri_t* bins, global const uint* page_table, uint page_first,
                        int4 rect) {
  uint c = get_global_id(0);
  if (c >= chunks) return;
  uint tri_count = record_count(triangle_total, capacity, extra);
  uint tiles = tiles_x * tiles_y;
  uint last = min((c + 1) * chunk_size, tri_count);
  for (uint i = c * chunk_size; i < last; ++i) {
    global const tri_t* r = tris + i;
    if (box_empty(r)) continue;
    FOR_BOX_TILES(r, tx, ty) {
      uint tile = ty * tiles_x + tx;
      if (DRAWN(tile)) bins[tile_base[tile] + COUNTER(tile, c)++] = *r;
    }
  }
}

// Covered pixels of the record in the clipped box [x_lo, x_hi] x [y_lo, y_hi], edge functions in
// type T (int only where they provably fit: see raster_tiles). Branch-free inner loop, so that
// it vectorizes.
#define RASTER_BOX(T)                                                                             \
  {                                                                                               \
    T sx0 = (T)(r->y1 - r->y2) * 256, sy0 = (T)(r->x2 - r->x1) * 256;                             \
    T sx1 = (T)(r->y2 - r->y0) * 256, sy1 = (T)(r->x0 - r->x2) * 256;                             \
    T sx2 = (T)(r->y0 - r->y1) * 256, sy2 = (T)(r->x1 - r->x0) * 256;                             \
    long px = ((long)x_lo << SUBPIXEL_BITS) + 128, py = ((long)y_lo << SUBPIXEL_BITS) + 128;      \
    T e0 = (T)(edge(r->x1, r->y1, r->x2, r->y2, px, py) + fill_bias(r->x1, r->y1, r->x2, r->y2)); \
    T e1 = (T)(edge(r->x2, r->y2, r->x0, r->y0, px, py) + fill_bias(r->x2, r->y2, r->x0, r->y0)); \
    T e2 = (T)(edge(r->x0, r->y0, r->x1, r->y1, px, py) + fill_bias(r->x0, r->y0, r->x1, r->y1)); \
    for (int y = y_lo; y <= y_hi; ++y, e0 += sy0, e1 += sy1, e2 += sy2) {                         \
      float zrow = plane_row(r->z0, r->dzdy, fy0, y);                                             \
      int row = (y - ty0) * TILE - tx0;                                                           \
      for (int x = x_lo; x <= x_hi; ++x) {                                                        \
        T k = (T)(x - x_lo);                                                                      \
        bool in = ((e0 + k * sx0) | (e1 + k * sx1) | (e2 + k * sx2)) >= 0;                        \
        float z = plane_at(zrow, r->dzdx, fx0, x);                                                \
        DEPTH_WRITE(row + x, in, z, r->prim)                                                      \
      }                                                                                           \
    }                                                                                             \
  }

// RASTER_BOX(int) for boxes at most NARROW pixels wide: a fixed number of lanes per row (those
// past x_hi are masked off and write back what they read; the tile buffers have NARROW spare
// texels for the last row), so the row is one vector operation instead of a scalar loop that a
// vectorizer leaves to its remainder. Edge values of the spare lanes stay below 2^29 + 2^26.
#define NARROW 16
#define RASTER_NARROW                                                                            \
  {                                                                                              \
    int sx0 = (r->y1 - r->y2) * 256, sy0 = (r->x2 - r->x1) * 256;                                \
    int sx1 = (r->y2 - r->y0) * 256, sy1 = (r->x0 - r->x2) * 256;                                \
    int sx2 = (r->y0 - r->y1) * 256, sy2 = (r->x1 - r->x0) * 256;                                \
    long px = ((long)x_lo << SUBPIXEL_BITS) + 128, py = ((long)y_lo << SUBPIXEL_BITS) + 128;     \
    int e0 =                                                                                     \
        (int)(edge(r->x1, r->y1, r->x2, r->y2, px, py) + fill_bias(r->x1, r->y1, r->x2, r->y2)); \
    int e1 =                                                                                     \
        (int)(edge(r->x2, r->y2, r->x0, r->y0, px, py) + fill_bias(r->x2, r->y2, r->x0, r->y0)); \
    int e2 =                                                                                     \
        (int)(edge(r->x0, r->y0, r->x1, r->y1, px, py) + fill_bias(r->x0, r->y0, r->x1, r->y1)); \
    int span = x_hi - x_lo;                                                                      \
    for (int y = y_lo; y <= y_hi; ++y, e0 += sy0, e1 += sy1, e2 += sy2) {                        \
      float zrow = plane_row(r->z0, r->dzdy, fy0, y);                                            \
      int row = (y - ty0) * TILE + (x_lo - tx0);                                                 \
      for (int k = 0; k < NARROW; ++k) {                                                         \
        bool in = k <= span && ((e0 + k * sx0) | (e1 + k * sx1) | (e2 + k * sx2)) >= 0;          \
        float z = plane_at(zrow, r->dzdx, fx0, x_lo + k);                                        \
        DEPTH_WRITE(row + k, in, z, r->prim)                                                     \
      }                                                                                          \
    }                                                                                            \
  }

// Whether the record covers the pixel centre (x, y).
inline bool covers(global const tri_t* r, int x, int y) {
  return covers_centre(r->x0, r->y0, r->x1, r->y1, r->x2, r->y2, x, y);
}

// Paths (build options; each only changes speed, raster_test compares it with the plain one):
//   FULL_TILE   an empty tile is written straight out; a record covering a whole tile (its four
//               corner pixel centres: the tile lies in the triangle, which is convex) writes its
//               plane in rows without edge tests
//   SMALL32     records less than 64 pixels across use 32-bit edge functions: every value
//               inside their box is below 2 * 2^14 * 2^14 = 2^29 in magnitude; boxes up to
//               NARROW pixels wide take fixed-width rows (RASTER_NARROW)
//   POINT_PATH  a record whose box holds one pixel centre tests just that pixel
//   HIZ         tile_far bounds every texel's depth once a record covered the whole tile;
//               records whose plane is beyond it over their box (less a rounding margin) skip
#ifndef FULL_TILE
#define FULL_TILE 1
#endif
#ifndef SMALL32
#define SMALL32 1
#endif
#ifndef POINT_PATH
#define POINT_PATH 1
#endif
#ifndef HIZ
#define HIZ 1
#endif

// A tile's row of n texels to the map, written once and read only by later passes. On PoCL's CPU
// device a whole row (whole cache lines) goes out in non-temporal stores: a map larger than the
// cache then costs no read-for-ownership of its lines (the 4096^2 raster ~1.2x faster; the SAT
// does the same). The same bits either way. V: the 16-wide vector of the texel type.
#ifdef CLANG_CPU_BUILTINS
#define STORE_ROW(V, dst, src, n)                                                   \
  {                                                                                 \
    if ((n) == TILE && ((ulong)(dst)&63) == 0) {                                    \
      for (int x = 0; x < TILE; x += 16)                                            \
        __builtin_nontemporal_store(vload16(0, (src) + x), (global V*)((dst) + x)); \
    } else {                                                                        \
      for (int x = 0; x < (n); ++x) (dst)[x] = (src)[x];                            \
    }                                                                               \
  }
#else
#define STORE_ROW(V, dst, src, n) \
  for (int x = 0; x < (n); ++x) (dst)[x] = (src)[x];
#endif

__attribute__((reqd_work_group_size(1, 1, 1))) kernel void raster_tiles(
    global const tri_t* bins, global const ulong* tile_base, uint tiles_x, uint width, uint height,
    global const uint2* draws, uint draw_first, global float* depth_out
#ifdef WRITE_ID
    ,
    global uint* id_out
#endif
) {
  uint slot;
  uint tile = raster_tile(get_global_id(0), draws, draw_first, tiles_x, &slot);
  int tx0 = (tile % tiles_x) * TILE, ty0 = (tile / tiles_x) * TILE;
  int tw = min(TILE, (int)width - tx0), th = min(TILE, (int)height - ty0);
  if (tw <= 0 || th <= 0) return;
  const ulong first = tile_base[tile], end = tile_base[tile + 1];
#if FULL_TILE
  if (first == end) {
    for (int y = 0; y < th; ++y)
      for (int x = 0; x < tw; ++x) {
        size_t o = texel_index(slot, tx0 + x, ty0 + y, width);
        depth_out[o] = 1.0f;
#ifdef WRITE_ID
        id_out[o] = 0xffffffffu;
#endif
      }
    return;
  }
#endif
  float depth[TILE * TILE + NARROW];
#ifdef WRITE_ID
  uint ids[TILE * TILE + NARROW];
#endif
  for (int i = 0; i < TILE * TILE + NARROW; ++i) {
    depth[i] = 1.0f;
#ifdef WRITE_ID
    ids[i] = 0xffffffffu;
#endif
  }
#if HIZ
  float tile_far = 1.0f;  // no texel of the tile is deeper
#endif
  for (ulong e = first; e < end; ++e) {
    global const tri_t* r = bins + e;
    int x_lo = max((int)r->min_x, tx0), x_hi = min((int)r->max_x, tx0 + tw - 1);
    int y_lo = max((int)r->min_y, ty0), y_hi = min((int)r->max_y, ty0 + th - 1);
    if (x_lo > x_hi || y_lo > y_hi) continue;
    float fx0 = r->x0 / SUBPIXEL, fy0 = r->y0 / SUBPIXEL;
#if HIZ
    if (tile_far < 1.0f &&
        plane_behind(r->z0, r->dzdx, r->dzdy, fx0, fy0, x_lo, x_hi, y_lo, y_hi, tile_far))
      continue;
#endif
#if POINT_PATH
    if (x_lo == x_hi && y_lo == y_hi) {
      if (covers(r, x_lo, y_lo)) {
        float z = plane_at(plane_row(r->z0, r->dzdy, fy0, y_lo), r->dzdx, fx0, x_lo);
        DEPTH_WRITE((y_lo - ty0) * TILE + (x_lo - tx0), true, z, r->prim)
      }
      continue;
    }
#endif
#if FULL_TILE
    if (x_lo == tx0 && y_lo == ty0 && x_hi == tx0 + tw - 1 && y_hi == ty0 + th - 1 &&
        covers(r, x_lo, y_lo) && covers(r, x_hi, y_lo) && covers(r, x_lo, y_hi) &&
        covers(r, x_hi, y_hi)) {
#if HIZ
      float far[TILE];  // per column: a reduction across x would not vectorize
      for (int x = 0; x < TILE; ++x) far[x] = 0.0f;
#endif
      for (int y = 0; y < th; ++y) {
        float zrow = plane_row(r->z0, r->dzdy, fy0, ty0 + y);
        for (int x = 0; x < tw; ++x) {
          float z = plane_at(zrow, r->dzdx, fx0, tx0 + x);
          DEPTH_WRITE(y * TILE + x, true, z, r->prim)
#if HIZ
          far[x] = fmax(far[x], depth[y * TILE + x]);
#endif
        }
      }
#if HIZ
      tile_far = 0.0f;
      for (int x = 0; x < tw; ++x) tile_far = fmax(tile_far, far[x]);
#endif
      continue;
    }
#endif
#if SMALL32
    int ext_x = max(r->x0, max(r->x1, r->x2)) - min(r->x0, min(r->x1, r->x2));
    int ext_y = max(r->y0, max(r->y1, r->y2)) - min(r->y0, min(r->y1, r->y2));
    if (ext_x < (1 << 14) && ext_y < (1 << 14)) {
      if (x_hi - x_lo < NARROW)
        RASTER_NARROW
      else
        RASTER_BOX(int)
      continue;
    }
#endif
    RASTER_BOX(long)
  }
  for (int y = 0; y < th; ++y) {
    size_t o = texel_index(slot, tx0, ty0 + y, width);
    STORE_ROW(float16, depth_out + o, depth + y * TILE, tw)
#ifdef WRITE_ID
    STORE_ROW(uint16, id_out + o, ids + y * TILE, tw)
#endif
  }
}

// ---- GPU shape ----
// Depth rasterization, GPU shape (issue 42), after Laine & Karras 2011 ("High-Performance
// Software Rasterization on GPUs"). Transform and set-up are the CPU shape's kernels built with a
// vertex and a triangle per work-item (-DVERTEX_CHUNK=1 -DTRIANGLE_CHUNK=1 -DVECTOR_SETUP=0), so
// the records are the same; binning and the raster are these:
//   bin_gpu_count    a work-item per record: atomic counts per tile, the boxes' pixels per group
//   bin_gpu_scan     one work-group: the tiles' first entries and the totals the CPU shape's
//                    bin_scan_totals gives (entries, box pixels, records wanted), which the
//                    host reads
//   bin_gpu_scatter  a work-item per record: copies into its tiles' lists at atomic cursors
//   raster_gpu_tiles a work-group per TILE x TILE tile: the group stages the tile's records in
//                    local memory, GROUP at a time; each work-item owns a BLOCK_W x BLOCK_H block
//                    of the tile, its depths (and ids) in registers, and tests every record
//                    whose box meets the block
// The lists' order depends on the atomics, but the result does not: a texel keeps the least
// depth and, among equal depths, the lowest id (DEPTH_WRITE), and every pixel's coverage and
// depth are the same integer and float expressions as the CPU shape's (both shapes' functions
// above). So both shapes write the same bits. Hierarchical z (HIZ) is per block: once a record
// covered the whole block, records behind its deepest texel are skipped.

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif
#ifndef HIZ
#define HIZ 1
#endif
// A tile's work-items: 16 across (a row of BLOCK_W-pixel blocks spans the tile, so a warp's
// writes are whole rows), GROUP / 16 down.
#define ITEMS_X 16
#define ITEMS_Y (GROUP / ITEMS_X)
#define BLOCK_W (TILE / ITEMS_X)
#define BLOCK_H (TILE / ITEMS_Y)
#if GROUP < ITEMS_X || TILE % ITEMS_X != 0 || TILE % ITEMS_Y != 0
#error "the GPU shape needs GROUP a power of two from 16 to 16 * TILE"
#endif

// Work-item = record i: each tile its box meets counts it once; group_pixels[g] = the pixels of
// group g's boxes (the raster's load). Group indices come from the global id: a sliced launch's
// offset does not enter get_group_id.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void bin_gpu_count(
    global const tri_t* tris, uint triangle_total, uint capacity, global const uint* extra,
    uint tiles_x, volatile global uint* tile_count, global ulong* group_pixels,
    global const uint* page_table, uint page_first, int4 rect) {
  local ulong pixels[GROUP];
  uint i = get_global_id(0), lid = get_local_id(0);
  uint tri_count = record_count(triangle_total, capacity, extra);
  ulong mine = 0;
  if (i < tri_count && !box_empty(tris + i)) {
    global const tri_t* r = tris + i;
    mine = box_pixels(r, 0);
    FOR_BOX_TILES(r, tx, ty)
    if (DRAWN(ty * tiles_x + tx)) atomic_inc(tile_count + ty * tiles_x + tx);
  }
  pixels[lid] = mine;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) pixels[lid] += pixels[lid + span];
  }
  if (lid == 0) group_pixels[i / GROUP] = pixels[0];
}

// One work-group: tile_base[t] = the first list entry of tile t (an exclusive scan of the
// counts, each work-item a run of tiles); tile_base[tiles] = every entry, tile_base[tiles + 1] =
// every box pixel, tile_base[tiles + 2] = the records set-up wanted. 64-bit, so that the host can
// refuse (not wrap) bins that would not fit.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void bin_gpu_scan(
    global const uint* tile_count, uint tiles, global const ulong* group_pixels, uint groups,
    uint triangle_total, global const uint* extra, global ulong* tile_base) {
  local ulong sums[GROUP];
  uint lid = get_local_id(0);
  uint run = (tiles + GROUP - 1) / GROUP;
  uint t0 = min(lid * run, tiles), t1 = min(t0 + run, tiles);
  ulong own = 0;
  for (uint t = t0; t < t1; ++t) own += tile_count[t];
  sums[lid] = own;
  barrier(CLK_LOCAL_MEM_FENCE);
  // Hillis-Steele inclusive scan of the runs' sums.
  for (uint span = 1; span < GROUP; span *= 2) {
    ulong add = lid >= span ? sums[lid - span] : 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    sums[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  ulong at = sums[lid] - own;
  for (uint t = t0; t < t1; ++t) {
    tile_base[t] = at;
    at += tile_count[t];
  }
  if (lid == GROUP - 1) tile_base[tiles] = sums[lid];
  barrier(CLK_LOCAL_MEM_FENCE);
  ulong pixels = 0;
  for (uint g = lid; g < groups; g += GROUP) pixels += group_pixels[g];
  sums[lid] = pixels;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) sums[lid] += sums[lid + span];
  }
  if (lid == 0) {
    tile_base[tiles + 1] = sums[0];
    tile_base[tiles + 2] = records_wanted(triangle_total, extra);
  }
}

// Work-item = record i, copied into each of its tiles' lists; `cursor` starts at zero.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void bin_gpu_scatter(
    global const tri_t* tris, uint triangle_total, uint capacity, global const uint* extra,
    uint tiles_x, volatile global uint* cursor, global const ulong* tile_base, global tri_t* bins,
    global const uint* page_table, uint page_first, int4 rect) {
  uint i = get_global_id(0);
  if (i >= record_count(triangle_total, capacity, extra) || box_empty(tris + i)) return;
  global const tri_t* r = tris + i;
  FOR_BOX_TILES(r, tx, ty) {
    uint tile = ty * tiles_x + tx;
    if (DRAWN(tile)) bins[tile_base[tile] + atomic_inc(cursor + tile)] = *r;
  }
}

// Work-group = tile (get_global_id(0) / GROUP), work-item = a BLOCK_W x BLOCK_H block of it.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void raster_gpu_tiles(
    global const tri_t* bins, global const ulong* tile_base, uint tiles_x, uint width, uint height,
    global const uint2* draws, uint draw_first, global float* depth_out
#ifdef WRITE_ID
    ,
    global uint* id_out
#endif
) {
  local tri_t batch[GROUP];
  uint slot, lid = get_local_id(0);
  uint tile = raster_tile(get_global_id(0) / GROUP, draws, draw_first, tiles_x, &slot);
  int bx0 = (tile % tiles_x) * TILE + (lid % ITEMS_X) * BLOCK_W;
  int by0 = (tile / tiles_x) * TILE + (lid / ITEMS_X) * BLOCK_H;
  float depth[BLOCK_W * BLOCK_H];
#ifdef WRITE_ID
  uint ids[BLOCK_W * BLOCK_H];
#endif
#pragma unroll
  for (int i = 0; i < BLOCK_W * BLOCK_H; ++i) {
    depth[i] = 1.0f;
#ifdef WRITE_ID
    ids[i] = 0xffffffffu;
#endif
  }
#if HIZ
  float block_far = 1.0f;  // no texel of the block is deeper
#endif
  const ulong first = tile_base[tile], end = tile_base[tile + 1];
  for (ulong base = first; base < end; base += GROUP) {
    uint n = (uint)min((ulong)GROUP, end - base);
    barrier(CLK_LOCAL_MEM_FENCE);  // the last batch is done with
    if (lid < n) batch[lid] = bins[base + lid];
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint k = 0; k < n; ++k) {
      local const tri_t* r = batch + k;
      int x_lo = max((int)r->min_x, bx0), x_hi = min((int)r->max_x, bx0 + BLOCK_W - 1);
      int y_lo = max((int)r->min_y, by0), y_hi = min((int)r->max_y, by0 + BLOCK_H - 1);
      if (x_lo > x_hi || y_lo > y_hi) continue;
      float fx0 = r->x0 / SUBPIXEL, fy0 = r->y0 / SUBPIXEL;
#if HIZ
      if (block_far < 1.0f &&
          plane_behind(r->z0, r->dzdx, r->dzdy, fx0, fy0, x_lo, x_hi, y_lo, y_hi, block_far))
        continue;
#endif
      // Edge functions at the block's first pixel centre and their steps per pixel: exact in 64
      // bits (the CPU shape's reasoning), so coverage is the CPU shape's to the last pixel.
      long px = ((long)bx0 << SUBPIXEL_BITS) + 128, py = ((long)by0 << SUBPIXEL_BITS) + 128;
      long e0 = edge(r->x1, r->y1, r->x2, r->y2, px, py) + fill_bias(r->x1, r->y1, r->x2, r->y2);
      long e1 = edge(r->x2, r->y2, r->x0, r->y0, px, py) + fill_bias(r->x2, r->y2, r->x0, r->y0);
      long e2 = edge(r->x0, r->y0, r->x1, r->y1, px, py) + fill_bias(r->x0, r->y0, r->x1, r->y1);
      long sx0 = (long)(r->y1 - r->y2) * 256, sy0 = (long)(r->x2 - r->x1) * 256;
      long sx1 = (long)(r->y2 - r->y0) * 256, sy1 = (long)(r->x0 - r->x2) * 256;
      long sx2 = (long)(r->y0 - r->y1) * 256, sy2 = (long)(r->x1 - r->x0) * 256;
      bool whole = true;  // the record covers every texel of the block
#pragma unroll
      for (int j = 0; j < BLOCK_H; ++j) {
        int y = by0 + j;
        float zrow = plane_row(r->z0, r->dzdy, fy0, y);
#pragma unroll
        for (int i = 0; i < BLOCK_W; ++i) {
          int x = bx0 + i;
          bool in =
              x >= x_lo && x <= x_hi && y >= y_lo && y <= y_hi &&
              ((e0 + i * sx0 + j * sy0) | (e1 + i * sx1 + j * sy1) | (e2 + i * sx2 + j * sy2)) >= 0;
          whole = whole && in;
          float z = plane_at(zrow, r->dzdx, fx0, x);
          DEPTH_WRITE(j * BLOCK_W + i, in, z, r->prim)
        }
      }
#if HIZ
      if (whole) {
        block_far = 0.0f;
#pragma unroll
        for (int i = 0; i < BLOCK_W * BLOCK_H; ++i) block_far = fmax(block_far, depth[i]);
      }
#endif
    }
  }
#pragma unroll
  for (int j = 0; j < BLOCK_H; ++j)
#pragma unroll
    for (int i = 0; i < BLOCK_W; ++i) {
      int x = bx0 + i, y = by0 + j;
      if (x >= (int)width || y >= (int)height) continue;
      size_t o = texel_index(slot, x, y, width);
      depth_out[o] = depth[j * BLOCK_W + i];
#ifdef WRITE_ID
      id_out[o] = ids[j * BLOCK_W + i];
#endif
    }
}
