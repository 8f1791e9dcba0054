// Summed-area tables, GPU shape (issue 42): the table sat.cl makes, bit for bit, with the work
// spread over the whole device instead of one work-item per 1024-pixel strip walking every row.
//
// Why the two directions differ. The table is the column sum of each row's running prefix
// rounded to the quantum 2^-k (sat.cl). The column sums add exact multiples of the quantum that
// stay below 2^52 quanta, so they are exact in any order: blocks of 64 rows are summed in
// parallel, the blocks' sums scanned down each column, and the blocks walked again from there.
// The row prefix, though, is rounded in double before it is quantized (float texels of very
// different magnitudes do not add exactly), and a prefix that lands near a half quantum rounds by
// its last bit (on 2100x5 texels of mixed magnitudes, a Hillis-Steele scan of each row and a
// sequential one quantized 9 of the 10 500 prefixes a quantum apart). So the rows are summed in
// sat.cl's own order, strip by strip, in parallel over rows, strips and (where sat.cl sums them
// one at a time) channels.
//
// Passes: strip sums and the largest |value| per work-group (sat_gpu_row_sums), the largest of
// those (sat_gpu_max; then sat.cl's own sat_scale picks the quantum), each (row, strip)'s
// quantized running prefix written into the table (sat_gpu_rows), then the column sums in place
// (sat_gpu_column_sums, sat_gpu_column_offsets, sat_gpu_column_scan). Indices are 32-bit (64-bit
// division is slow on GPUs): a table is under 2^28 doubles (2 GiB). Exact whenever the texture is
// finite (an infinite texel makes the quantum 1 and the sums inexact, in either variant). NaN
// texels count as 0.

#include "sat_common.cl"

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
// channels + c], summed as sat.cl's sat_row_sums does; the work-group's largest |value| in
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

// A work-item per (row, strip), or per (row, strip, channel) where sat.cl sums channels one at a
// time: the quantized running prefix of the row, starting from the strips to its left (summed
// as sat.cl's sat_strip_offsets does), in the table's place. sat.cl's sat_scan without its walk
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

// sat.cl's sat_box with a work-item per texel (its channels in turn): the same sums and division.
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
