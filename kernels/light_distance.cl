// The distance from a point (a point light) to the nearest triangle of a set of draws, as one
// minimum per chunk of triangles: a lower bound for the near planes of the light's cube faces
// (engine/light/cube_fit.hpp). The host takes the minimum of the few partial results.

#define TRIANGLE_CHUNK 1024

// Squared distance from the origin to triangle abc (Ericson, Real-Time Collision Detection,
// 5.1.5, with the query point at the origin).
inline float origin_triangle_distance2(float3 a, float3 b, float3 c) {
  float3 ab = b - a, ac = c - a, ap = -a;
  float d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return dot3(a, a);
  float3 bp = -b;
  float d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return dot3(b, b);
  float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    float3 q = a + ab * (d1 / (d1 - d3));
    return dot3(q, q);
  }
  float3 cp = -c;
  float d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return dot3(c, c);
  float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    float3 q = a + ac * (d2 / (d2 - d6));
    return dot3(q, q);
  }
  float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    float3 q = b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    return dot3(q, q);
  }
  float denom = 1.0f / (va + vb + vc);
  float3 q = a + ab * (vb * denom) + ac * (vc * denom);
  return dot3(q, q);
}

// chunk_min[g] = the smallest distance from `point` to triangles [g * 1024, (g + 1) * 1024),
// minus a bound of the float error (so it stays a lower bound), at least 0. A work-group per
// chunk: one work-item on the CPU shape, GROUP (the profile's, as -DGROUP) on the GPU shape, whose
// work-items take every GROUP-th triangle and then reduce in local memory. The least squared
// distance and the largest coordinate are exact in any order, so both shapes give the same bits.
#ifndef GROUP
#define GROUP 1
#endif
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void min_triangle_distance(
    global const float* positions, global const uint* indices, global const draw_t* draws,
    uint draw_count, uint triangle_count, float4 point, global float* chunk_min) {
  local float best2s[GROUP], scales[GROUP];
  uint lid = get_local_id(0), chunk = get_global_id(0) / GROUP;
  uint first = chunk * TRIANGLE_CHUNK;
  uint last = min(first + TRIANGLE_CHUNK, triangle_count);
  uint d = find_draw(draws, draw_count, min(first + lid, triangle_count - 1), 1);
  float best2 = INFINITY, scale = 0.0f;
  for (uint t = first + lid; t < last; t += GROUP) {
    while (d + 1 < draw_count && draws[d + 1].out_triangle_base <= t) ++d;
    float3 a, b, c;
    world_triangle(positions, indices, draws + d, t, &a, &b, &c);
    best2 = fmin(best2, origin_triangle_distance2(a - point.xyz, b - point.xyz, c - point.xyz));
    scale = fmax(scale, fmax(fmax(fabs(a.x), fabs(a.y)), fabs(a.z)));
    scale = fmax(scale, fmax(fmax(fabs(b.x), fabs(b.y)), fabs(b.z)));
    scale = fmax(scale, fmax(fmax(fabs(c.x), fabs(c.y)), fabs(c.z)));
  }
  best2s[lid] = best2, scales[lid] = scale;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) {
      best2s[lid] = fmin(best2s[lid], best2s[lid + span]);
      scales[lid] = fmax(scales[lid], scales[lid + span]);
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid != 0) return;
  // The transform and the differences carry errors of a few ulps of the coordinates' size.
  scale = fmax(scales[0], fmax(fmax(fabs(point.x), fabs(point.y)), fabs(point.z)));
  chunk_min[chunk] = fmax(sqrt(best2s[0]) - 1e-5f * scale, 0.0f);
}
