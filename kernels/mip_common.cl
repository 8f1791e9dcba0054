// What mip.cl (the CPU shape) and mip_gpu.cl (the GPU shape, issue 42) share: the texel type and
// the averages, the same operations in the same order, so both shapes make the same bits.

// MIP_HALF (CSM bases stored as half floats): texels are read with vload_half and written with
// vstore_half; the arithmetic stays float.
#ifdef MIP_HALF
typedef half mip_t;
#define MIP_LOAD(p, i) vload_half((i), (p))
#define MIP_STORE(v, p, i) vstore_half((v), (i), (p))
#else
typedef float mip_t;
#define MIP_LOAD(p, i) ((p)[i])
#define MIP_STORE(v, p, i) ((p)[i] = (v))
#endif

// NaN-aware mean of four texels (v != v: NaN), the sum in a fixed order.
inline float mean4(float v0, float v1, float v2, float v3) {
  float n = (v0 != v0 ? 0.0f : 1.0f) + (v1 != v1 ? 0.0f : 1.0f) + (v2 != v2 ? 0.0f : 1.0f) +
            (v3 != v3 ? 0.0f : 1.0f);
  float s = (v0 != v0 ? 0.0f : v0) + (v1 != v1 ? 0.0f : v1) + (v2 != v2 ? 0.0f : v2) +
            (v3 != v3 ? 0.0f : v3);
  return n > 0.0f ? s / n : NAN;
}

// Channel c of destination texel (i, j) in the general (not 2:1) case: the area-weighted mean of
// source rows [ya, yb) and columns [xa, xb), NaN texels left out.
inline float footprint_mean(global const mip_t* src, uint w, uint h, uint channels, uint c, uint w2,
                            uint h2, uint i, uint j, uint xa, uint xb, uint ya, uint yb) {
  float s = 0.0f, wsum = 0.0f;
  for (uint y = ya; y < yb; ++y) {
    float wy = (float)(min((y + 1) * h2, (j + 1) * h) - max(y * h2, j * h));
    for (uint x = xa; x < xb; ++x) {
      float wx = (float)(min((x + 1) * w2, (i + 1) * w) - max(x * w2, i * w));
      float v = MIP_LOAD(src, ((size_t)y * w + x) * channels + c);
      if (!isnan(v)) {
        s += wx * wy * v;
        wsum += wx * wy;
      }
    }
  }
  return wsum > 0.0f ? s / wsum : NAN;
}
