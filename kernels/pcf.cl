// Percentage-closer filtering of the shadow test: the visibilities of several texels are averaged
// (never the depths). Bilinear 2x2 weighs the four texels around the point like a bilinear
// lookup; Poisson-disk PCF averages N taps within a radius, optionally rotated per pixel. Each
// tap compares the receiver plane's depth at that tap (the plane's gradient per texel), so wide
// kernels do not self-shadow tilted planes. Pixels are classified as in shadow_test.cl.

#define PIXEL_CHUNK 64
#define LIGHT_SPOT 1
#define PCF_BILINEAR 0
#define PCF_POISSON 1

// 1 lit, 0 shadowed; texels off the map are lit (the map covers every caster).
inline float texel_test(global const float* map, int size, int i, int j, float z) {
  if (i < 0 || j < 0 || i >= size || j >= size) return 1.0f;
  return z <= map[(size_t)j * size + i] ? 1.0f : 0.0f;
}

// Interleaved gradient noise (Jimenez 2014): a rotation angle per pixel without a texture.
inline float pixel_angle(uint p, uint width) {
  float x = (float)(p % width), y = (float)(p / width);
  float a = 0.06711056f * x + 0.00583715f * y;
  a = 52.9829189f * (a - floor(a));
  return 6.2831853f * (a - floor(a));
}

kernel void pcf(global const float* position, global const float4* normal, uint pixel_count,
                uint width, float16 light_to_ndc, global const float* map, uint map_size,
                float bias_constant, float bias_slope, int light_kind, float4 light_position,
                float4 light_axis, float cos_half_cone, int mode, global const float2* taps,
                uint tap_count, float radius, int rotate, global float* visibility) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, pixel_count);
  int size = (int)map_size;
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    float4 n = normal[p];
    float vis;
    if (isnan(x.x)) {
      vis = NAN;
    } else if (light_kind == LIGHT_SPOT &&
               dot(normalize(x - light_position.xyz), light_axis.xyz) < cos_half_cone) {
      vis = 0.0f;
    } else if (n.w == 0.0f) {
      vis = 1.0f;
    } else {
      float4 c = mul_m4(light_to_ndc, (float4)(x, 1.0f));
      float3 s = c.xyz / c.w;
      float u = s.x * map_size, v = s.y * map_size;
      if (c.w <= 0.0f || u < 0.0f || v < 0.0f || u >= map_size || v >= map_size) {
        vis = 1.0f;
      } else {
        float2 g = depth_gradient(light_to_ndc, n.xyz, c, map_size);
        g = isfinite(g.x) && isfinite(g.y) ? clamp(g, -MAX_SLOPE, MAX_SLOPE) : (float2)(0.0f);
        float z = s.z - (bias_constant + bias_slope * fmin(fabs(g.x) + fabs(g.y), MAX_SLOPE));
        if (mode == PCF_BILINEAR) {
          float tx = u - 0.5f, ty = v - 0.5f;
          int i = (int)floor(tx), j = (int)floor(ty);
          float fx = tx - i, fy = ty - j;
          // Receiver-plane depth at each texel centre, relative to the point.
          float dz0 = -g.x * fx - g.y * fy;
          float v00 = texel_test(map, size, i, j, z + dz0);
          float v10 = texel_test(map, size, i + 1, j, z + dz0 + g.x);
          float v01 = texel_test(map, size, i, j + 1, z + dz0 + g.y);
          float v11 = texel_test(map, size, i + 1, j + 1, z + dz0 + g.x + g.y);
          vis = mix(mix(v00, v10, fx), mix(v01, v11, fx), fy);
        } else {
          float cs = 1.0f, sn = 0.0f;
          if (rotate) sn = sincos(pixel_angle(p, width), &cs);
          float sum = 0.0f;
          for (uint k = 0; k < tap_count; ++k) {
            float2 t = taps[k];
            float2 d = radius * (float2)(cs * t.x - sn * t.y, sn * t.x + cs * t.y);
            sum += texel_test(map, size, (int)floor(u + d.x), (int)floor(v + d.y),
                              z + g.x * d.x + g.y * d.y);
          }
          vis = sum / tap_count;
        }
      }
    }
    visibility[p] = vis;
  }
}
