// The per-pixel shadow test: 1 = lit, 0 = shadowed, NaN where the camera sees nothing.
// Visibility is occlusion only (no N.L term); outside a spot light's cone it is 0.

#define PIXEL_CHUNK 64
#define LIGHT_DIRECTIONAL 0
#define LIGHT_SPOT 1
// Slope bias stays finite where the receiver is edge-on to the light.
#define MAX_SLOPE 1.0f

// The receiver plane's NDC-depth change per shadow-map texel, |dz/du| + |dz/dv|, from the
// point's position and normal through the light's world_to_ndc (exact for planes, any matrix).
inline float depth_slope(float16 m, float3 p, float3 n, float4 c, float map_size) {
  float3 t1 = fabs(n.x) < 0.9f ? cross(n, (float3)(1, 0, 0)) : cross(n, (float3)(0, 1, 0));
  t1 = normalize(t1);
  float3 t2 = cross(n, t1);
  float4 m1 = mul_m4(m, (float4)(t1, 0.0f)), m2 = mul_m4(m, (float4)(t2, 0.0f));
  float3 ndc = c.xyz / c.w;
  float3 d1 = (m1.xyz - ndc * m1.w) / c.w, d2 = (m2.xyz - ndc * m2.w) / c.w;
  float det = d1.x * d2.y - d2.x * d1.y;
  if (det == 0.0f) return MAX_SLOPE;
  float gx = (d1.z * d2.y - d2.z * d1.y) / det, gy = (d1.x * d2.z - d2.x * d1.z) / det;
  return fmin((fabs(gx) + fabs(gy)) / map_size, MAX_SLOPE);
}

kernel void shadow_test(global const float* position, global const float4* normal, uint pixel_count,
                        float16 light_to_ndc, global const float* map, uint map_size,
                        float bias_constant, float bias_slope, int light_kind,
                        float4 light_position, float4 light_axis, float cos_half_cone,
                        global float* visibility) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, pixel_count);
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    float4 n = normal[p];
    float vis;
    if (isnan(x.x)) {
      vis = NAN;
    } else if (light_kind == LIGHT_SPOT &&
               dot(normalize(x - light_position.xyz), light_axis.xyz) < cos_half_cone) {
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
        float bias = bias_constant + bias_slope * depth_slope(light_to_ndc, x, n.xyz, c, map_size);
        vis = (s.z - bias <= map[(size_t)j * map_size + i]) ? 1.0f : 0.0f;
      }
    }
    visibility[p] = vis;
  }
}
