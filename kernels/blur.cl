// Ping-pong blur (Kozlov, GPU Gems 14.4.2). While the shadow map renders, the nearest
// primitive per texel gives one-hot receiver-class planes (1 where the surface nearest to the
// light is an instance of class k); a separable Gaussian blurs them back and forth between two
// buffers; receivers of class k then read plane k bilinearly instead of the depth test.
// Planes are stored one after another (plane k at k * width * height), so a horizontal pass sees
// planes * height rows and no pass needs barriers or atomics.

// The GPU shape (engine/passes/pixel_shape.hpp) builds this file with -DPIXEL_CHUNK=1: a
// work-item per texel or pixel, in work-groups, each one's arithmetic as here.
#ifdef PIXEL_CHUNK
#define STRIP PIXEL_CHUNK
#else
#define STRIP 64
#endif
#define NO_PRIMITIVE 0xffffffffu

kernel void blur_classes(global const uint* ids, global const draw_t* draws, uint draw_count,
                         uint texels, uint planes, global float* out) {
  uint first = get_global_id(0) * STRIP;
  uint last = min(first + STRIP, texels);
  for (uint t = first; t < last; ++t) {
    uint id = ids[t];
    int cls = -1;  // empty texel or an instance without a class
    if (id != NO_PRIMITIVE) {
      uint d = find_draw(draws, draw_count, id, 1);
      cls = (int)((draws[d].flags >> DRAW_CLASS_SHIFT) & 0xffu) - 1;
    }
    for (uint k = 0; k < planes; ++k) out[(size_t)k * texels + t] = cls == (int)k ? 1.0f : 0.0f;
  }
}

// Taps outside, pixels inside: the inner loop is contiguous and vectorizes. Edges clamp (the
// border texel repeats), and taps are summed from -radius to +radius in that order.
kernel void blur_rows(global const float* src, global float* dst, uint width, uint rows,
                      uint strips, global const float* weights, int radius) {
  uint g = get_global_id(0);
  uint row = g / strips, x0 = (g % strips) * STRIP;
  if (row >= rows) return;
  uint n = min((uint)STRIP, width - x0);
  global const float* s = src + (size_t)row * width;
  float acc[STRIP];
  for (uint i = 0; i < STRIP; ++i) acc[i] = 0.0f;
  for (int k = -radius; k <= radius; ++k) {
    float w = weights[k + radius];
    for (uint i = 0; i < n; ++i) acc[i] += w * s[clamp((int)(x0 + i) + k, 0, (int)width - 1)];
  }
  global float* d = dst + (size_t)row * width + x0;
  for (uint i = 0; i < n; ++i) d[i] = acc[i];
}

kernel void blur_columns(global const float* src, global float* dst, uint width, uint height,
                         uint planes, uint strips, global const float* weights, int radius) {
  uint g = get_global_id(0);
  uint x0 = (g % strips) * STRIP, row = g / strips;  // row over planes * height
  if (row >= planes * height) return;
  uint y = row % height;
  size_t base = (size_t)(row - y) * width + x0;  // the plane's first row, at x0
  uint n = min((uint)STRIP, width - x0);
  float acc[STRIP];
  for (uint i = 0; i < STRIP; ++i) acc[i] = 0.0f;
  for (int k = -radius; k <= radius; ++k) {
    float w = weights[k + radius];
    global const float* s = src + base + (size_t)clamp((int)y + k, 0, (int)height - 1) * width;
    for (uint i = 0; i < n; ++i) acc[i] += w * s[i];
  }
  global float* d = dst + (size_t)row * width + x0;
  for (uint i = 0; i < n; ++i) d[i] = acc[i];
}

// Overwrites the hard test's visibility of class receivers (normal.w = 2 + class) with their
// blurred plane, sampled bilinearly (texel centres at (i + 0.5) / size, edges clamped), capped by
// the share of the light's disk above their horizon. Pixels outside a spot's cone, facing away
// from the whole disk or off the map keep what the hard test gave them (0, 0 and 1).
kernel void blur_visibility(global const float* position, global const float4* normal,
                            uint pixel_count, shadow_lookup_t lookup, global const float* blurred,
                            global float* visibility) {
  uint first = get_global_id(0) * STRIP;
  uint last = min(first + STRIP, pixel_count);
  float16 light_to_ndc = lookup.to_ndc;
  uint map_size = lookup.map_size;
  int m = (int)map_size - 1;
  for (uint p = first; p < last; ++p) {
    float w = normal[p].w;
    if (!(w >= 2.0f)) continue;  // no class, not a receiver, or nothing seen (NaN)
    float3 x = vload3(p, position);
    // Outside the cone or facing away: the hard test's 0 stands.
    float above = disk_above_horizon(x, normal[p].xyz, &lookup.light);
    if (outside_spot_cone(x, &lookup.light) || above == 0.0f) continue;
    float4 c = mul_m4(light_to_ndc, (float4)(x, 1.0f));
    float2 s = c.xy / c.w;
    if (c.w <= 0.0f || s.x < 0.0f || s.y < 0.0f || s.x >= 1.0f || s.y >= 1.0f) continue;
    float fx = s.x * map_size - 0.5f, fy = s.y * map_size - 0.5f;
    float ix = floor(fx), iy = floor(fy);
    float ax = fx - ix, ay = fy - iy;
    int i0 = clamp((int)ix, 0, m), i1 = clamp((int)ix + 1, 0, m);
    int j0 = clamp((int)iy, 0, m), j1 = clamp((int)iy + 1, 0, m);
    global const float* plane = blurred + (size_t)((int)w - 2) * map_size * map_size;
    float top = lerp(plane[(size_t)j0 * map_size + i0], plane[(size_t)j0 * map_size + i1], ax);
    float bottom = lerp(plane[(size_t)j1 * map_size + i0], plane[(size_t)j1 * map_size + i1], ax);
    visibility[p] = fmin(lerp(top, bottom, ay), above);
  }
}
