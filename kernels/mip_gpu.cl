// Mip pyramids, GPU shape (issue 42): a work-item per destination texel (its channels in turn),
// one launch per level. The same arithmetic as mip.cl's mip_downsample in the same order (see
// there for the footprints and weights), so the same bits; only the work per work-item differs.
// Texel indices are 32-bit (64-bit division is slow on GPUs; a level has under 2^32 texels).

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif

// MIP_HALF (CSM bases stored as half floats), as in mip.cl.
#ifdef MIP_HALF
typedef half mip_t;
#define MIP_LOAD(p, i) vload_half((i), (p))
#define MIP_STORE(v, p, i) vstore_half((v), (i), (p))
#else
typedef float mip_t;
#define MIP_LOAD(p, i) ((p)[i])
#define MIP_STORE(v, p, i) ((p)[i] = (v))
#endif

// mip.cl's NaN-aware mean of four texels, the sum in the same fixed order.
inline float mean4(float v0, float v1, float v2, float v3) {
  float n = (v0 != v0 ? 0.0f : 1.0f) + (v1 != v1 ? 0.0f : 1.0f) + (v2 != v2 ? 0.0f : 1.0f) +
            (v3 != v3 ? 0.0f : 1.0f);
  float s = (v0 != v0 ? 0.0f : v0) + (v1 != v1 ? 0.0f : v1) + (v2 != v2 ? 0.0f : v2) +
            (v3 != v3 ? 0.0f : v3);
  return n > 0.0f ? s / n : NAN;
}

// src and dst may be regions of one buffer (the chain), hence the offsets in elements.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void mip_gpu_downsample(
    global const mip_t* src, ulong src_offset, uint w, uint h, uint channels, global mip_t* dst,
    ulong dst_offset, uint w2, uint h2) {
  src += src_offset;
  dst += dst_offset;
  uint texel = get_global_id(0);
  if (texel >= w2 * h2) return;
  uint i = texel % w2, j = texel / w2;
  size_t out = (size_t)texel * channels;
  if (w == 2 * w2 && h == 2 * h2) {
    size_t a = ((size_t)(2 * j) * w + 2 * i) * channels, pitch = (size_t)w * channels;
    for (uint c = 0; c < channels; ++c) {
      size_t a0 = a + c, b0 = a0 + channels;
      MIP_STORE(mean4(MIP_LOAD(src, a0), MIP_LOAD(src, b0), MIP_LOAD(src, a0 + pitch),
                      MIP_LOAD(src, b0 + pitch)),
                dst, out + c);
    }
    return;
  }
  uint ya = j * h / h2, yb = ((j + 1) * h + h2 - 1) / h2;
  uint xa = i * w / w2, xb = ((i + 1) * w + w2 - 1) / w2;
  for (uint c = 0; c < channels; ++c) {
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
    MIP_STORE(wsum > 0.0f ? s / wsum : NAN, dst, out + c);
  }
}
