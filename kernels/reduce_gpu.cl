// Reductions over the camera view, GPU shape (issue 42): reduce.cl's view_depth_partials and
// boundary_cells with a work-group per chunk or cell instead of a work-item. The work-items read
// pixels GROUP apart (adjacent work-items, adjacent pixels), then reduce in local memory. Minima,
// maxima and integer counts are exact in any order, so each result is reduce.cl's.

#include "reduce_common.cl"

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif
#define DEPTH_CHUNK 4096  // pixels per partial, as in reduce.cl

// Work-group g = pixels [g * DEPTH_CHUNK, (g + 1) * DEPTH_CHUNK): partials[g] = (min, max) view
// depth of those that receive shadows (+inf, -inf where none does).
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void view_depth_partials_gpu(
    global const float* position, global const float4* normal, uint pixel_count, float4 eye,
    float4 forward, global float2* partials) {
  local float lo[GROUP], hi[GROUP];
  uint lid = get_local_id(0), chunk = get_global_id(0) / GROUP;
  uint first = chunk * DEPTH_CHUNK, last = min(first + DEPTH_CHUNK, pixel_count);
  global const float* nrm = (global const float*)normal;
  float l = INFINITY, h = -INFINITY;
  for (uint p = first + lid; p < last; p += GROUP) {
    float x = position[3 * p], y = position[3 * p + 1], z = position[3 * p + 2];
    float d = view_depth(x, y, z, eye.x, eye.y, eye.z, forward.x, forward.y, forward.z);
    int receives = receives_shadows(x, y, z, nrm[4 * p + 3]);
    l = receives ? fmin(l, d) : l;
    h = receives ? fmax(h, d) : h;
  }
  lo[lid] = l, hi[lid] = h;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span)
      lo[lid] = fmin(lo[lid], lo[lid + span]), hi[lid] = fmax(hi[lid], hi[lid + span]);
  }
  if (lid == 0) partials[chunk] = (float2)(lo[0], hi[0]);
}

// Work-group = cell i of the columns x rows grid: (seen pixels, boundary pixels), as
// reduce.cl's boundary_cells counts them.
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
