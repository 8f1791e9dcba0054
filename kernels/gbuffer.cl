// Camera-view surfaces: world position and geometric normal of the nearest primitive at each
// pixel, found by intersecting the pixel's ray with that primitive's plane (exact, and
// perspective-correct without interpolating anything).

#define PIXEL_CHUNK 64
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
      n = normalize(cross(b - a, c - a));
      // w: 0 = receives no shadows, 1 = the filter's depth test, 2 + k = blur receiver class
      // k. Other passes only test w != 0.
      uint flags = draws[d].flags;
      w = (flags & DRAW_RECEIVES) ? 1.0f + ((flags >> DRAW_CLASS_SHIFT) & 0xffu) : 0.0f;
      held = id;
    }
    float u = ((p % width) + 0.5f) / width, v = ((p / width) + 0.5f) / (pixel_count / width);
    float3 o = eye.xyz, dir = ray_00.xyz + u * ray_du.xyz + v * ray_dv.xyz;
    float t = dot(n, a - o) / dot(n, dir);
    float3 facing = n;
    if (dot(n, dir) > 0.0f) facing = -n;  // face the camera
    vstore3(o + t * dir, p, position_out);
    normal_out[p] = (float4)(facing, w);
  }
}
