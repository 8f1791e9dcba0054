// Mip pyramids, GPU shape (issue 42): a work-item per destination texel (its channels in turn),
// one launch per level. The same arithmetic as mip.cl's mip_downsample in the same order (see
// there for the footprints and weights), so the same bits; only the work per work-item differs.
// Texel indices are 32-bit (64-bit division is slow on GPUs; a level has under 2^32 texels).

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif

#include "mip_common.cl"

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
