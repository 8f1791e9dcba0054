// What sat.cl (the CPU shape) and sat_gpu.cl (the GPU shape, issue 42) share: the helpers whose
// operations and order make the table's bits, so both shapes make the same table.
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
