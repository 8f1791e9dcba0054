// Summed-area tables (SATs) of float textures, any size and channel count (channels interleaved).
//
// Representation: doubles holding exact multiples of a power-of-two quantum 2^-k. Each row's
// running prefix r(x) is computed in double and rounded to the quantum once, so the stored table
// is the exact SAT of a texture whose texels differ from the input by at most two quanta: every
// column sum is then an exact integer multiple of the quantum (k is chosen so that W*H*max|v|
// stays below 2^51 quanta), and box sums lose nothing to the distance from the origin. At 8192^2
// with values in [0, 1] the quantum is 2^-26: box averages are good to a few 1e-8.
//
// Three passes: row sums per (strip, band) and the largest |value| (sat_row_sums), their
// exclusive prefix across strips and the quantum (sat_strip_offsets, sat_scale), then one
// work-item per 256-pixel strip walks down all rows (sat_scan). NaN texels count as 0.

#include "sat_common.cl"

#define SAT_BAND 64  // rows per sat_row_sums work-item
#define SAT_MAX_CHANNELS 64

// One work-item per band of rows, every strip of each row in turn (whole rows: the reads stream
// through memory; a strip per work-item jumped a row pitch every 1 KB and stalled the
// prefetcher): row_sums[(y * strips + s) * channels + c] and the band's max |value| in
// item_max[band].
__attribute__((reqd_work_group_size(1, 1, 1))) kernel void sat_row_sums(global const float* src,
                                                                        uint width, uint height,
                                                                        uint channels, uint strips,
                                                                        global double* row_sums,
                                                                        global double* item_max) {
  uint item = get_global_id(0);
  uint y0 = item * SAT_BAND;
  if (y0 >= height) return;
  uint y1 = min(y0 + SAT_BAND, height);
  float8 m8 = 0.0f;
  double m = 0.0;
  for (uint y = y0; y < y1; ++y)
    for (uint s = 0; s < strips; ++s) {
      uint x0 = s * SAT_STRIP, x1 = min(x0 + SAT_STRIP, width);
      strip_sums(src + ((size_t)y * width + x0) * channels, (x1 - x0) * channels, channels,
                 row_sums + ((size_t)y * strips + s) * channels, &m8, &m);
    }
  float mm[8];
  vstore8(m8, 0, mm);
  for (uint l = 0; l < 8; ++l) m = fmax(m, (double)mm[l]);
  item_max[item] = m;
}

// One work-item per 64 rows: row_sums becomes the exclusive prefix across strips (the sum of
// everything left of each strip, per row and channel).
kernel void sat_strip_offsets(global double* row_sums, uint height, uint channels, uint strips) {
  uint y0 = get_global_id(0) * 64, y1 = min(y0 + 64, height);
  for (uint y = y0; y < y1; ++y) {
    for (uint c = 0; c < channels; ++c) {
      double off = 0.0;
      for (uint s = 0; s < strips; ++s) {
        size_t i = ((size_t)y * strips + s) * channels + c;
        double t = row_sums[i];
        row_sums[i] = off;
        off += t;
      }
    }
  }
}

// One work-item: scale[0] = 2^k, scale[1] = 2^-k with W*H*max|v| * 2^k < 2^51 (ROUNDER's range).
kernel void sat_scale(global const double* item_max, uint items, uint width, uint height,
                      global double* scale) {
  double m = 0.0;
  for (uint i = 0; i < items; ++i) m = fmax(m, item_max[i]);
  double bound = m * (double)width * (double)height;
  int k = 0;
  if (bound > 0.0 && isfinite(bound)) {
    int e;
    frexp(bound, &e);  // bound < 2^e
    k = 51 - e;
  }
  scale[0] = ldexp(1.0, k);
  scale[1] = ldexp(1.0, -k);
}

// sat_scan for one channel: the strip's previous row is kept in a private array instead of being
// read back from the table, so the table is only written, with non-temporal stores where aligned
// (no read-for-ownership of 8 bytes per texel). Same arithmetic, so the same table.
inline void scan_one_channel(global const float* src, uint width, uint height, uint strips, uint s,
                             global const double* offsets, double q, double inv_q,
                             global double* sat) {
  uint x0 = s * SAT_STRIP, n = min(x0 + SAT_STRIP, width) - x0, nv = n & ~7u;
  double col[SAT_STRIP];  // the strip's row y - 1 of the table
  for (uint e = 0; e < SAT_STRIP; ++e) col[e] = 0.0;
  bool aligned = ((width | x0) & 7) == 0 && ((ulong)sat & 63) == 0;  // for CLANG_CPU_BUILTINS
  for (uint y = 0; y < height; ++y) {
    global const float* in = src + (size_t)y * width + x0;
    global double* out = sat + (size_t)y * width + x0;
    double8 carry = (double8)(offsets[(size_t)y * strips + s]);
    for (uint e = 0; e < nv; e += 8) {
#ifdef CLANG_CPU_BUILTINS
      // Each row of the strip starts a new page, where the hardware prefetcher restarts: fetch
      // two rows ahead (prefetches never fault, so the last rows need no test). OpenCL's own
      // prefetch() does nothing on PoCL; clang's builtin is PoCL-only (program_cache.cpp).
      __builtin_prefetch(in + e + 2 * (size_t)width);
#endif
      double8 v = scan8(sanitize8(vload8(0, in + e)), 1) + carry;
      carry = (double8)(v.s7);
      double8 r = round8(v * q) * inv_q + vload8(0, col + e);
      vstore8(r, 0, col + e);
#ifdef CLANG_CPU_BUILTINS
      if (aligned)
        __builtin_nontemporal_store(r, (global double8*)(out + e));
      else
#endif
        vstore8(r, 0, out + e);
    }
    double run = carry.s0;
    for (uint e = nv; e < n; ++e) {
      run += sanitize(in[e]);
      col[e] += ((run * q + ROUNDER) - ROUNDER) * inv_q;
      out[e] = col[e];
    }
  }
}

// One work-item per strip, down every row: sat = previous row + quantized running row prefix.
__attribute__((reqd_work_group_size(1, 1, 1))) kernel void sat_scan(
    global const float* src, uint width, uint height, uint channels, uint strips,
    global const double* offsets, global const double* scale, global double* sat) {
  uint s = get_global_id(0);
  if (s >= strips) return;
  const double q = scale[0], inv_q = scale[1];
  if (channels == 1) {
    scan_one_channel(src, width, height, strips, s, offsets, q, inv_q, sat);
    return;
  }
  uint x0 = s * SAT_STRIP, x1 = min(x0 + SAT_STRIP, width);
  uint n = (x1 - x0) * channels;
  uint nv = vector_path(channels) ? n & ~7u : 0;
  size_t pitch = (size_t)width * channels;
  for (uint y = 0; y < height; ++y) {
    global const float* in = src + y * pitch + x0 * channels;
    global double* out = sat + y * pitch + x0 * channels;
    global const double* prev = out - pitch;  // read only when y > 0
    global const double* off = offsets + ((size_t)y * strips + s) * channels;
    double run[SAT_MAX_CHANNELS];
    for (uint c = 0; c < channels; ++c) run[c] = off[c];
    if (nv > 0) {
      double lanes[8];
      for (uint l = 0; l < 8; ++l) lanes[l] = run[l % channels];
      double8 carry = vload8(0, lanes);
      for (uint e = 0; e < nv; e += 8) {
        double8 v = scan8(sanitize8(vload8(0, in + e)), channels) + carry;
        carry = carry8(v, channels);
        double8 r = round8(v * q) * inv_q;
        if (y > 0) r += vload8(0, prev + e);
        vstore8(r, 0, out + e);
      }
      vstore8(carry, 0, lanes);
      for (uint c = 0; c < channels; ++c) run[c] = lanes[c];
    }
    for (uint e = nv; e < n; ++e) {
      uint c = e % channels;
      run[c] += sanitize(in[e]);
      double r = ((run[c] * q + ROUNDER) - ROUNDER) * inv_q;
      out[e] = y > 0 ? prev[e] + r : r;
    }
  }
}

// The average of each channel over the (2 rx + 1) x (2 ry + 1) box around each texel, clipped to
// the texture. One work-item per 64 texels of a row.
kernel void sat_box(global const double* sat, uint width, uint height, uint channels, uint rx,
                    uint ry, global float* out) {
  uint chunks = (width + 63) / 64;
  uint y = get_global_id(0) / chunks;
  if (y >= height) return;
  uint x_first = get_global_id(0) % chunks * 64, x_last = min(x_first + 64, width);
  int ya = (int)y - (int)ry - 1, yb = min(y + ry, height - 1);
  size_t pitch = (size_t)width * channels;
  for (uint x = x_first; x < x_last; ++x) {
    int xa = (int)x - (int)rx - 1, xb = min(x + rx, width - 1);
    for (uint c = 0; c < channels; ++c)
      out[(size_t)y * pitch + (size_t)x * channels + c] =
          box_average(sat, pitch, channels, c, xa, xb, ya, yb);
  }
}
