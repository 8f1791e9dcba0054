// float32 -> IEEE binary16 rounded to nearest even: the float16 outputs (RenderRequest
// output_format), converted on the device so half the bytes are read back and sent. NaN stays
// NaN, +-inf stays, finite values past the half range become +-inf (IEEE).
// The GPU shape (engine/passes/pixel_shape.hpp) builds it with -DPIXEL_CHUNK=1: a value per
// work-item.
#ifdef PIXEL_CHUNK
#define HALF_CHUNK PIXEL_CHUNK
#else
#define HALF_CHUNK 4096  // values per work-item, as HalfPackPass::kChunk
#endif

__kernel void pack_half(__global const float* src, uint first, uint count, __global half* dst) {
  const uint begin = get_global_id(0) * HALF_CHUNK;
  const uint end = min(begin + HALF_CHUNK, count);
  for (uint i = begin; i < end; ++i) vstore_half_rte(src[first + i], i, dst);
}
