// Camera-view surfaces: world position and geometric normal of the nearest primitive at each
// pixel, found by intersecting the pixel's ray with that primitive's plane (exact, and
// perspective-correct without interpolating anything).

// The GPU shape (engine/passes/pixel_shape.hpp) builds this same kernel with -DPIXEL_CHUNK=1 and
// launches it in work-groups: a work-item per pixel, each pixel's arithmetic and bits as here.
#ifndef PIXEL_CHUNK
#define PIXEL_CHUNK 64
#endif
#define NO_PRIMITIVE 0xffffffffu

// The ray through texture point (u, v) (0..1 from the top-left) runs from the eye along
// ray_00 + u * ray_du + v * ray_dv, built from the camera's basis in double on the host:
// unprojecting through an inverted float matrix would lose digits when far/near is large.
kernel void resolve_gbuffer(global const uint* ids, uint width, uint pixel_count, float4 eye,
                            float4 ray_00, float4 ray_du, float4 ray_dv,
                            global const float* positions, global const uint* indices,
                            global const draw_t* draws, uint draw_count, global float* position_out,
                            global float4* normal_out) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, pixel_count);
  // Neighbouring pixels mostly see the same primitive: its plane and flags are fetched and
  // computed once per run of equal ids (the same expressions, so the same bits).
  uint held = NO_PRIMITIVE;
  float3 a = (float3)(0.0f), n = (float3)(0.0f);
  float w = 0.0f;
  for (uint p = first; p < last; ++p) {
    uint id = ids[p];
    if (id == NO_PRIMITIVE) {
      vstore3((float3)(NAN), p, position_out);
      normal_out[p] = (float4)(NAN);
      continue;
    }
    if (id != held) {
      uint d = find_draw(draws, draw_count, id, 1);
      float3 b, c;
      world_triangle(positions, indices, draws + d, id, &a, &b, &c);
      n = normalize3(cross3(b - a, c - a));
      // w: 0 = receives no shadows, 1 = the filter's depth test, 2 + k = blur receiver class
      // k. Other passes only test w != 0.
      uint flags = draws[d].flags;
      w = (flags & DRAW_RECEIVES) ? 1.0f + ((flags >> DRAW_CLASS_SHIFT) & 0xffu) : 0.0f;
      held = id;
    }
    float u = ((p % width) + 0.5f) / width, v = ((p / width) + 0.5f) / (pixel_count / width);
    // The ray and its hit in fma steps: one rounding each, which far/near ratios of 1e6 need
    // (LiSPSM's ratio_1e6_along test: 99 px misclassified this way, 110 in separate steps).
    float3 o = eye.xyz;
    float3 dir = fma((float3)(v), ray_dv.xyz, fma((float3)(u), ray_du.xyz, ray_00.xyz));
    float t = dot3(n, a - o) / dot3(n, dir);
    float3 facing = n;
    if (dot3(n, dir) > 0.0f) facing = -n;  // face the camera
    vstore3(fma((float3)(t), dir, o), p, position_out);
    normal_out[p] = (float4)(facing, w);
  }
}
