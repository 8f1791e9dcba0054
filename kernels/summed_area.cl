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

// ---- Both shapes: the same operations in the same order, so the same bits ----

#pragma OPENCL EXTENSION cl_khr_fp64 : enable

#define SAT_STRIP 1024  // pixels per strip: 4 KB of floats per row, a page for the prefetcher

inline double8 sanitize8(float8 v) {
  return convert_double8(select(v, (float8)(0.0f), isnan(v)));
}
inline double sanitize(float v) {
  return isnan(v) ? 0.0 : (double)v;
}

// Inclusive prefix of each channel within 8 lanes (lane l holds channel l % c, c in {1,2,4,8}).
inline double8 scan8(double8 v, uint c) {
  if (c == 1) v += (double8)(0.0, v.s012, v.s3456);
  if (c <= 2) v += (double8)(0.0, 0.0, v.s0123, v.s45);
  if (c <= 4) v += (double8)((double4)(0.0), v.s0123);
  return v;
}
// The running totals of the last pixel, repeated across the lanes.
inline double8 carry8(double8 v, uint c) {
  if (c == 1) return (double8)(v.s7);
  if (c == 2) return v.s67676767;
  if (c == 4) return v.s45674567;
  return v;
}
// Round to the nearest integer: exact for |x| < 2^51, and cheaper than rint on double8 here.
#define ROUNDER 6755399441055744.0  // 1.5 * 2^52
inline double8 round8(double8 x) {
  return (x + ROUNDER) - ROUNDER;
}
inline bool vector_path(uint c) {
  return c == 1 || c == 2 || c == 4 || c == 8;
}

// One strip of one row (n floats, channels interleaved, starting at `row`): the sum of each
// channel into sums[c], and the largest |value| into *m8 (the vector lanes) and *m (the rest).
inline void strip_sums(global const float* row, uint n, uint channels, global double* sums,
                       float8* m8, double* m) {
  uint nv = vector_path(channels) ? n & ~7u : 0;
  double8 acc8 = 0.0;
  for (uint e = 0; e < nv; e += 8) {
    float8 f = vload8(0, row + e);
    f = select(f, (float8)(0.0f), isnan(f));
    acc8 += convert_double8(f);
    float8 a = select(f, -f, f < 0.0f);
    *m8 = select(*m8, a, a > *m8);
  }
  double acc[8];
  vstore8(acc8, 0, acc);
  for (uint c = 0; c < channels; ++c) {
    double a = 0.0;
    for (uint l = c; l < 8 && nv > 0; l += channels) a += acc[l];
    for (uint e = nv + c; e < n; e += channels) {
      double v = sanitize(row[e]);
      a += v;
      *m = fmax(*m, fabs(v));
    }
    sums[c] = a;
  }
}

// The average of channel c over the box (xa, xb] x (ya, yb] of the table (xa, ya = -1: from the
// texture's edge), `pitch` doubles per row.
inline float box_average(global const double* sat, size_t pitch, uint channels, uint c, int xa,
                         int xb, int ya, int yb) {
  double area = (double)(xb - max(xa, -1)) * (double)(yb - max(ya, -1));
  double sum = sat[yb * pitch + (size_t)xb * channels + c];
  if (xa >= 0) sum -= sat[yb * pitch + (size_t)xa * channels + c];
  if (ya >= 0) sum -= sat[(size_t)ya * pitch + (size_t)xb * channels + c];
  if (xa >= 0 && ya >= 0) sum += sat[(size_t)ya * pitch + (size_t)xa * channels + c];
  return (float)(sum / area);
}

// ---- CPU shape ----

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

// ---- GPU shape ----
// Summed-area tables, GPU shape (issue 42): the table the CPU shape makes, bit for bit, with the
// work spread over the whole device instead of one work-item per 1024-pixel strip walking every
// row.
//
// Why the two directions differ. The table is the column sum of each row's running prefix
// rounded to the quantum 2^-k (above). The column sums add exact multiples of the quantum that
// stay below 2^52 quanta, so they are exact in any order: blocks of 64 rows are summed in
// parallel, the blocks' sums scanned down each column, and the blocks walked again from there.
// The row prefix, though, is rounded in double before it is quantized (float texels of very
// different magnitudes do not add exactly), and a prefix that lands near a half quantum rounds by
// its last bit (on 2100x5 texels of mixed magnitudes, a Hillis-Steele scan of each row and a
// sequential one quantized 9 of the 10 500 prefixes a quantum apart). So the rows are summed in
// the CPU shape's own order, strip by strip, in parallel over rows, strips and (where the CPU shape
// sums them one at a time) channels.
//
// Passes: strip sums and the largest |value| per work-group (sat_gpu_row_sums), the largest of
// those (sat_gpu_max; then the CPU shape's own sat_scale picks the quantum), each (row, strip)'s
// quantized running prefix written into the table (sat_gpu_rows), then the column sums in place
// (sat_gpu_column_sums, sat_gpu_column_offsets, sat_gpu_column_scan). Indices are 32-bit (64-bit
// division is slow on GPUs): a table is under 2^28 doubles (2 GiB). Exact whenever the texture is
// finite (an infinite texel makes the quantum 1 and the sums inexact, in either variant). NaN
// texels count as 0.

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif
#define SAT_BLOCK_ROWS 64  // rows per work-item of the column pass

// The largest of every work-item's `m` in the work-group, in work-item 0's return value.
inline double group_max(double m, local double* scratch) {
  uint lid = get_local_id(0);
  scratch[lid] = m;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) scratch[lid] = fmax(scratch[lid], scratch[lid + span]);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  return scratch[0];
}

// A work-item per (row, strip): the strip's sum per channel in row_sums[(y * strips + s) *
// channels + c], summed as sat_row_sums does; the work-group's largest |value| in
// item_max[group].
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void sat_gpu_row_sums(
    global const float* src, uint width, uint height, uint channels, uint strips,
    global double* row_sums, global double* item_max) {
  local double scratch[GROUP];
  uint item = get_global_id(0);
  double m = 0.0;
  if (item < height * strips) {
    uint y = item / strips, s = item % strips;
    uint x0 = s * SAT_STRIP, x1 = min(x0 + SAT_STRIP, width);
    float8 m8 = 0.0f;
    strip_sums(src + ((size_t)y * width + x0) * channels, (x1 - x0) * channels, channels,
               row_sums + (size_t)item * channels, &m8, &m);
    float mm[8];
    vstore8(m8, 0, mm);
    for (uint l = 0; l < 8; ++l) m = fmax(m, (double)mm[l]);
  }
  m = group_max(m, scratch);
  if (get_local_id(0) == 0) item_max[item / GROUP] = m;
}

// One work-group: out[0] = the largest of item_max[0 .. items) (a max: any order gives it).
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void sat_gpu_max(
    global const double* item_max, uint items, global double* out) {
  local double scratch[GROUP];
  double m = 0.0;
  for (uint i = get_local_id(0); i < items; i += GROUP) m = fmax(m, item_max[i]);
  m = group_max(m, scratch);
  if (get_local_id(0) == 0) out[0] = m;
}

// A work-item per (row, strip), or per (row, strip, channel) where the CPU shape sums channels one
// at a time: the quantized running prefix of the row, starting from the strips to its left (summed
// as sat_strip_offsets does), in the table's place. sat_scan without its walk
// down the rows: the same operations in the same order, so the same values.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void sat_gpu_rows(
    global const float* src, uint width, uint height, uint channels, uint strips,
    global const double* row_sums, global const double* scale, global double* sat) {
  const bool vector = vector_path(channels);
  uint item = get_global_id(0);
  uint ch = 0;  // the one channel of this work-item, off the vector path
  if (!vector) {
    ch = item % channels;
    item /= channels;
  }
  if (item >= height * strips) return;
  uint y = item / strips, s = item % strips;
  const double q = scale[0], inv_q = scale[1];
  uint x0 = s * SAT_STRIP, x1 = min(x0 + SAT_STRIP, width);
  uint n = (x1 - x0) * channels;
  global const float* in = src + ((size_t)y * width + x0) * channels;
  global double* out = sat + ((size_t)y * width + x0) * channels;
  global const double* sums = row_sums + (size_t)y * strips * channels;
  if (!vector) {
    double run = 0.0;
    for (uint t = 0; t < s; ++t) run += sums[t * channels + ch];
    for (uint e = ch; e < n; e += channels) {
      run += sanitize(in[e]);
      out[e] = ((run * q + ROUNDER) - ROUNDER) * inv_q;
    }
    return;
  }
  double lanes[8];
  for (uint c = 0; c < channels; ++c) {
    double off = 0.0;
    for (uint t = 0; t < s; ++t) off += sums[t * channels + c];
    for (uint l = c; l < 8; l += channels) lanes[l] = off;
  }
  uint nv = n & ~7u;
  double8 carry = vload8(0, lanes);
  for (uint e = 0; e < nv; e += 8) {
    double8 v = scan8(sanitize8(vload8(0, in + e)), channels) + carry;
    carry = carry8(v, channels);
    vstore8(round8(v * q) * inv_q, 0, out + e);
  }
  vstore8(carry, 0, lanes);
  for (uint e = nv; e < n; ++e) {
    uint c = e % channels;
    lanes[c] += sanitize(in[e]);
    out[e] = ((lanes[c] * q + ROUNDER) - ROUNDER) * inv_q;
  }
}

// The column pass, over the table's doubles as columns (x * channels + c, `columns` of them):
// a work-item per (block of SAT_BLOCK_ROWS rows, column), adjacent work-items on adjacent
// columns. First each block's sum, in block_sums[block * columns + column].
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void sat_gpu_column_sums(
    global const double* sat, uint columns, uint height, global double* block_sums) {
  uint item = get_global_id(0);
  uint blocks = (height + SAT_BLOCK_ROWS - 1) / SAT_BLOCK_ROWS;
  if (item >= blocks * columns) return;
  uint column = item % columns, y0 = item / columns * SAT_BLOCK_ROWS;
  uint y1 = min(y0 + SAT_BLOCK_ROWS, height);
  double sum = 0.0;
  for (uint y = y0; y < y1; ++y) sum += sat[(size_t)y * columns + column];
  block_sums[item] = sum;
}

// A work-item per column: its blocks' sums become the sums of the blocks above each.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void sat_gpu_column_offsets(
    global double* block_sums, uint columns, uint blocks) {
  uint column = get_global_id(0);
  if (column >= columns) return;
  double run = 0.0;
  for (uint b = 0; b < blocks; ++b) {
    size_t i = (size_t)b * columns + column;
    double t = block_sums[i];
    block_sums[i] = run;
    run += t;
  }
}

// A work-item per (block, column) again: the running column sum down the block, from the sum
// of the blocks above it.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void sat_gpu_column_scan(
    global double* sat, uint columns, uint height, global const double* block_sums) {
  uint item = get_global_id(0);
  uint blocks = (height + SAT_BLOCK_ROWS - 1) / SAT_BLOCK_ROWS;
  if (item >= blocks * columns) return;
  uint column = item % columns, y0 = item / columns * SAT_BLOCK_ROWS;
  uint y1 = min(y0 + SAT_BLOCK_ROWS, height);
  double run = block_sums[item];
  for (uint y = y0; y < y1; ++y) {
    size_t i = (size_t)y * columns + column;
    run += sat[i];
    sat[i] = run;
  }
}

// sat_box with a work-item per texel (its channels in turn): the same sums and division.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void sat_gpu_box(global const double* sat,
                                                                           uint width, uint height,
                                                                           uint channels, uint rx,
                                                                           uint ry,
                                                                           global float* out) {
  uint texel = get_global_id(0);
  if (texel >= width * height) return;
  uint x = texel % width, y = texel / width;
  int ya = (int)y - (int)ry - 1, yb = min(y + ry, height - 1);
  int xa = (int)x - (int)rx - 1, xb = min(x + rx, width - 1);
  size_t pitch = (size_t)width * channels;
  for (uint c = 0; c < channels; ++c)
    out[(size_t)texel * channels + c] = box_average(sat, pitch, channels, c, xa, xb, ya, yb);
}
