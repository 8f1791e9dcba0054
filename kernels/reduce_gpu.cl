// Reductions over the camera view, GPU shape (issue 42): reduce.cl's view_depth_partials with a
// work-group per DEPTH_CHUNK pixels instead of a work-item. Its work-items read the chunk's
// pixels GROUP apart (adjacent work-items, adjacent pixels), then halve their running minima and
// maxima in local memory. A min and a max are exact in any order, so each partial is reduce.cl's.

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
