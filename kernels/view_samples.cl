// view_samples: the camera view's surface at the centres of a columns x rows grid of equal cells
// (pixel ((2c + 1) width / (2 columns), (2r + 1) height / (2 rows))), for a quality goal's error
// prediction (engine/passes/view_samples.hpp): position (NaN where nothing is seen), then the
// normal where the pixel receives shadows, else 0. One work-item per sample.
kernel void view_samples(global const float* position, global const float4* normal, uint width,
                         uint height, uint columns, uint rows, global float8* samples) {
  uint i = get_global_id(0);
  if (i >= columns * rows) return;
  uint c = i % columns, r = i / columns;
  uint x = (uint)(((ulong)(2 * c + 1) * width) / (2 * (ulong)columns));
  uint y = (uint)(((ulong)(2 * r + 1) * height) / (2 * (ulong)rows));
  uint p = y * width + x;
  float3 at = vload3(p, position);
  float4 n = normal[p];
  bool receives = n.w != 0.0f && !isnan(n.w);
  float3 facing = receives ? n.xyz : (float3)(0.0f);
  samples[i] = (float8)(at, 0.0f, facing, 0.0f);
}
