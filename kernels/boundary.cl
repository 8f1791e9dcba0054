// A camera view's shadow edges that a map can misplace (engine/passes/boundary.hpp): per cell of a
// grid over the view, the pixels seen and those on a shadow boundary of a lit surface.

// ---- Both shapes: the per-pixel tests, so both shapes count the same pixels ----

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

// ---- CPU shape: a work-item per cell ----

#define EDGE_CHUNK 64

kernel void boundary_cells(global const float* visibility, global const float* position,
                           global const float4* normal, uint width, uint height, uint columns,
                           uint rows, float4 eye, light_t light, global uint2* cells) {
  uint i = get_global_id(0);
  if (i >= columns * rows) return;
  uint c = i % columns, r = i / columns;
  uint x0 = (uint)(((ulong)c * width) / columns), x1 = (uint)(((ulong)(c + 1) * width) / columns);
  uint y0 = (uint)(((ulong)r * height) / rows), y1 = (uint)(((ulong)(r + 1) * height) / rows);
  uint seen = 0, boundary = 0;
  // Which 4-neighbours' visibility differs, per pixel of a chunk of a row: bit 0 left, 1 right,
  // 2 up, 3 down. Found in a loop that vectorizes; the surfaces are read only where one does.
  uchar changes[EDGE_CHUNK];
  for (uint y = y0; y < y1; ++y) {
    global const float* row = visibility + (size_t)y * width;
    global const float* up = y > 0 ? row - width : row;
    global const float* down = y + 1 < height ? row + width : row;
    for (uint first = x0; first < x1; first += EDGE_CHUNK) {
      uint n = min((uint)EDGE_CHUNK, x1 - first);
      uint any = 0;
      for (uint l = 0; l < n; ++l) {
        uint x = first + l;
        uint m = changes_at(row, up, down, x, width);
        bool is_seen = !isnan(row[x]);
        seen += is_seen ? 1u : 0u;
        changes[l] = is_seen ? (uchar)m : (uchar)0;
        any |= m;
      }
      if (!any) continue;  // the common case: no change in this chunk
      for (uint l = 0; l < n; ++l)
        if (changes[l])
          boundary +=
              on_boundary(position, normal, first + l, y, width, height, changes[l], eye, &light);
    }
  }
  cells[i] = (uint2)(seen, boundary);
}

// ---- GPU shape (issue 42): a work-group per cell; the work-items take its pixels GROUP apart,
// then add their counts in local memory (integers: exact in any order) ----

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif

// Work-group = cell i of the columns x rows grid: (seen pixels, boundary pixels), as
// boundary_cells counts them.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void boundary_cells_gpu(
    global const float* visibility, global const float* position, global const float4* normal,
    uint width, uint height, uint columns, uint rows, float4 eye, light_t light,
    global uint2* cells) {
  local uint seen[GROUP], boundary[GROUP];
  uint lid = get_local_id(0), i = get_global_id(0) / GROUP;
  uint c = i % columns, r = i / columns;
  uint x0 = (uint)(((ulong)c * width) / columns), x1 = (uint)(((ulong)(c + 1) * width) / columns);
  uint y0 = (uint)(((ulong)r * height) / rows), y1 = (uint)(((ulong)(r + 1) * height) / rows);
  uint cell_width = x1 - x0, own_seen = 0, own_boundary = 0;
  for (uint k = lid; k < cell_width * (y1 - y0); k += GROUP) {
    uint x = x0 + k % cell_width, y = y0 + k / cell_width;
    global const float* row = visibility + (size_t)y * width;
    uint m =
        changes_at(row, y > 0 ? row - width : row, y + 1 < height ? row + width : row, x, width);
    if (isnan(row[x])) continue;
    ++own_seen;
    if (m && on_boundary(position, normal, x, y, width, height, m, eye, &light)) ++own_boundary;
  }
  seen[lid] = own_seen, boundary[lid] = own_boundary;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) seen[lid] += seen[lid + span], boundary[lid] += boundary[lid + span];
  }
  if (lid == 0) cells[i] = (uint2)(seen[0], boundary[0]);
}
