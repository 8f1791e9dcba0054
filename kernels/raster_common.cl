// What raster.cl (the CPU shape) and raster_gpu.cl (the GPU shape, issue 42) share: the set-up's
// record, its coverage and its depth plane. Both shapes evaluate every pixel with these same
// functions, so they write the same bits.

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
