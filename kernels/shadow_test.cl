// The per-pixel shadow test: 1 = lit, 0 = shadowed, NaN where the camera sees nothing.
// Visibility is occlusion only (no N.L term); outside a spot light's cone it is 0. A cube face's
// launch writes only the pixels of its faces (owns_pixel) and leaves the others untouched.

#define PIXEL_CHUNK 64
kernel void shadow_test(global const float* position, global const float4* normal, uint pixel_count,
                        shadow_lookup_t lookup, global const float* map, faces_t faces,
                        global float* visibility) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, pixel_count);
  float16 light_to_ndc = lookup.to_ndc;
  uint map_size = lookup.map_size;
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    if (!owns_pixel(&faces, x.x, x.y, x.z)) continue;
    float4 n = normal[p];
    float vis;
    if (isnan(x.x)) {
      vis = NAN;
    } else if (outside_spot_cone(x, &lookup.light)) {
      vis = 0.0f;  // outside the cone: no light at all, receiver or not
    } else if (n.w == 0.0f) {
      vis = 1.0f;  // does not receive shadows
    } else {
      float4 c = mul_m4(light_to_ndc, (float4)(x, 1.0f));
      float3 s = c.xyz / c.w;
      int i = (int)floor(s.x * map_size), j = (int)floor(s.y * map_size);
      if (c.w <= 0.0f || i < 0 || j < 0 || i >= (int)map_size || j >= (int)map_size) {
        vis = 1.0f;  // the map covers every caster of the visible receivers
      } else {
        float bias = lookup.bias_constant +
                     lookup.bias_slope * depth_slope(light_to_ndc, x, n.xyz, c, map_size);
        vis = (s.z - bias <= map[(size_t)j * map_size + i]) ? 1.0f : 0.0f;
      }
    }
    visibility[p] = vis;
  }
}
