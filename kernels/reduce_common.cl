// What reduce.cl (the CPU shape) and reduce_gpu.cl (the GPU shape, issue 42) share: the boundary
// count's per-pixel tests, so both shapes count the same pixels.

// Whether a seen pixel at x with normal n (w: receives shadows) is lit as the hard test lights
// it: it receives shadows, lies inside a spot's cone and its seen side faces the light.
inline bool lit_side(float3 x, float4 n, const light_t* light) {
  float3 to_light = light->kind == LIGHT_DIRECTIONAL ? -light->axis.xyz : light->position.xyz - x;
  return n.w != 0.0f && dot3(n.xyz, to_light) > 0.0f && !outside_spot_cone(x, light);
}

// A seen pixel's surface, for on_lit_surface: its position, normal, whether it is lit, and the
// longest step to a 4-neighbour on its plane, squared: 3 times the step one pixel makes there,
// distance x pixel extent / cos(view angle), the cosine taken at least 0.05 (edge-on planes).
typedef struct {
  float3 x;
  float4 n;
  float reach2;
  bool lit;
} surface_t;

inline surface_t pixel_surface(global const float* position, global const float4* normal, uint p,
                               float4 eye, const light_t* light) {
  surface_t s;
  s.x = vload3(p, position);
  s.n = normal[p];
  s.lit = lit_side(s.x, s.n, light);
  float3 ray = s.x - eye.xyz;
  float d2 = dot3(ray, ray), f = dot3(ray, s.n.xyz);
  float facing2 = fmax(f * f / d2, 0.0025f);
  s.reach2 = 9.0f * d2 * eye.w * eye.w / facing2;
  return s;
}

// Whether seen 4-neighbour q lies on lit pixel s's lit surface, where a map's shadow edge between
// them could fall (boundary_cells): q is lit too, their normals within ~25 degrees, and q within
// s's reach. Elsewhere the lit/dark change is the geometry's (an attached shadow, the cone's rim,
// a silhouette or a crease), which a map does not move.
inline bool on_lit_surface(const surface_t* s, global const float* position,
                           global const float4* normal, uint q, const light_t* light) {
  float3 x = vload3(q, position), d = x - s->x;
  float4 n = normal[q];
  return dot3(s->n.xyz, n.xyz) > 0.9f && dot3(d, d) <= s->reach2 && lit_side(x, n, light);
}

// Which 4-neighbours of pixel x of `row` differ in visibility (by more than 1/2): bit 0 left,
// 1 right, 2 up, 3 down. A neighbour off the image is the pixel itself (`up`, `down` are `row`
// at the image's edges); NaN neighbours fail the comparison.
inline uint changes_at(global const float* row, global const float* up, global const float* down,
                       uint x, uint width) {
  float v = row[x];
  float left = row[x > 0 ? x - 1 : x], right = row[x + 1 < width ? x + 1 : x];
  return (fabs(v - left) > 0.5f ? 1u : 0u) | (fabs(v - right) > 0.5f ? 2u : 0u) |
         (fabs(v - up[x]) > 0.5f ? 4u : 0u) | (fabs(v - down[x]) > 0.5f ? 8u : 0u);
}

// Whether seen pixel (x, y), whose visibility changes towards the neighbours in mask m, lies on a
// shadow boundary a map could move: it is lit and one of those neighbours is on its lit surface.
inline bool on_boundary(global const float* position, global const float4* normal, uint x, uint y,
                        uint width, uint height, uint m, float4 eye, const light_t* light) {
  uint p = y * width + x;
  surface_t s = pixel_surface(position, normal, p, eye, light);
  if (!s.lit) return false;
  uint q[4] = {x > 0 ? p - 1 : p, x + 1 < width ? p + 1 : p, y > 0 ? p - width : p,
               y + 1 < height ? p + width : p};
  bool edge = false;
  for (uint k = 0; k < 4; ++k)
    edge = edge || ((m >> k & 1u) && on_lit_surface(&s, position, normal, q[k], light));
  return edge;
}
