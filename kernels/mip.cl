// Mip pyramids: each level is the area-weighted box filter of the level above, any size
// (non-power-of-two included) and any channel count (channels interleaved). Level l+1 is
// max(1, floor(w / 2)) x max(1, floor(h / 2)); destination texel i covers source
// [i * w / w2, (i + 1) * w / w2), so odd sizes blend three source texels with fractional weights.
// The weights are exact integers over w * h. NaN texels (visibility where the camera sees
// nothing) are left out of the average; a texel whose footprint is all NaN stays NaN.

// One work-item per MIP_CHUNK destination texels of one row, fixed local size 1: a CPU-sized
// chunk whose inner loop over texels LLVM vectorizes (no OpenCL vector types, no branches).
#define MIP_CHUNK 512

#include "mip_common.cl"

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
