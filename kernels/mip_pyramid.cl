// Mip pyramids: each level is the area-weighted box filter of the level above, any size
// (non-power-of-two included) and any channel count (channels interleaved). Level l+1 is
// max(1, floor(w / 2)) x max(1, floor(h / 2)); destination texel i covers source
// [i * w / w2, (i + 1) * w / w2), so odd sizes blend three source texels with fractional weights.
// The weights are exact integers over w * h. NaN texels (visibility where the camera sees
// nothing) are left out of the average; a texel whose footprint is all NaN stays NaN.

// ---- Both shapes: the same operations in the same order, so the same bits ----

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

// ---- CPU shape ----

// One work-item per MIP_CHUNK destination texels of one row, fixed local size 1: a CPU-sized
// chunk whose inner loop over texels LLVM vectorizes (no OpenCL vector types, no branches).
#define MIP_CHUNK 512

// The exact 2:1 case, the common one: the texel loop inside the channel loop so that it runs over
// texels (unit stride for one channel).
inline void halve_row(global const mip_t* src, uint w, uint channels, uint i0, uint i1, uint j,
                      global mip_t* dst, uint w2) {
  global const mip_t* r0 = src + (size_t)(2 * j) * w * channels;
  global const mip_t* r1 = r0 + (size_t)w * channels;
  global mip_t* out = dst + (size_t)j * w2 * channels;
  if (channels == 1) {
    for (uint i = i0; i < i1; ++i)
      MIP_STORE(mean4(MIP_LOAD(r0, 2 * i), MIP_LOAD(r0, 2 * i + 1), MIP_LOAD(r1, 2 * i),
                      MIP_LOAD(r1, 2 * i + 1)),
                out, i);
    return;
  }
  for (uint c = 0; c < channels; ++c) {
    for (uint i = i0; i < i1; ++i) {
      size_t a = (size_t)(2 * i) * channels + c, b = a + channels;
      MIP_STORE(mean4(MIP_LOAD(r0, a), MIP_LOAD(r0, b), MIP_LOAD(r1, a), MIP_LOAD(r1, b)), out,
                (size_t)i * channels + c);
    }
  }
}

// src and dst may be regions of one buffer (the chain), hence the offsets in floats.
__attribute__((reqd_work_group_size(1, 1, 1))) kernel void mip_downsample(
    global const mip_t* src, ulong src_offset, uint w, uint h, uint channels, global mip_t* dst,
    ulong dst_offset, uint w2, uint h2) {
  src += src_offset;
  dst += dst_offset;
  uint chunks = (w2 + MIP_CHUNK - 1) / MIP_CHUNK;
  uint j = get_global_id(0) / chunks;
  if (j >= h2) return;
  uint i0 = get_global_id(0) % chunks * MIP_CHUNK, i1 = min(i0 + MIP_CHUNK, w2);
  if (w == 2 * w2 && h == 2 * h2) {
    halve_row(src, w, channels, i0, i1, j, dst, w2);
    return;
  }
  // Footprint rows [j h / h2, (j + 1) h / h2) in units of 1 / h2.
  uint ya = j * h / h2, yb = ((j + 1) * h + h2 - 1) / h2;
  for (uint i = i0; i < i1; ++i) {
    uint xa = i * w / w2, xb = ((i + 1) * w + w2 - 1) / w2;
    for (uint c = 0; c < channels; ++c)
      MIP_STORE(footprint_mean(src, w, h, channels, c, w2, h2, i, j, xa, xb, ya, yb), dst,
                ((size_t)j * w2 + i) * channels + c);
  }
}

// ---- GPU shape ----
// Mip pyramids, GPU shape (issue 42): a work-item per destination texel (its channels in turn),
// one launch per level. The same arithmetic as mip_downsample in the same order (see
// there for the footprints and weights), so the same bits; only the work per work-item differs.
// Texel indices are 32-bit (64-bit division is slow on GPUs; a level has under 2^32 texels).

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif

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
  for (uint c = 0; c < channels; ++c)
    MIP_STORE(footprint_mean(src, w, h, channels, c, w2, h2, i, j, xa, xb, ya, yb), dst, out + c);
}
