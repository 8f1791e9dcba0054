// The visible receivers' view-depth range (PSM near-plane push, Kozlov 14.1.2 / the paper §6).
//
// view_depth_partials: the min and max view depth (distance along the camera's forward axis)
// over the pixels that receive shadows (G-buffer normal.w != 0, position not NaN). One work-item
// reduces one chunk of pixels to one partial (min, max); +inf / -inf where a chunk has none. The
// host combines the few hundred partials. No barriers, no atomics (slow on a CPU device).
// Within a chunk, DEPTH_LANES running minima and maxima, halved into one at the end
// (min_max_halving): one running pair made every pixel wait for the last.

// ---- CPU shape ----

#define DEPTH_CHUNK 4096
#define DEPTH_LANES 64

kernel void view_depth_partials(global const float* position, global const float4* normal,
                                uint pixel_count, float4 eye, float4 forward,
                                global float2* partials) {
  uint first = get_global_id(0) * DEPTH_CHUNK;
  uint last = min(first + DEPTH_CHUNK, pixel_count);
  float ex = eye.x, ey = eye.y, ez = eye.z, fx = forward.x, fy = forward.y, fz = forward.z;
  global const float* nrm = (global const float*)normal;
  float lo[DEPTH_LANES], hi[DEPTH_LANES];
  for (uint l = 0; l < DEPTH_LANES; ++l) lo[l] = INFINITY, hi[l] = -INFINITY;
  for (uint s = first; s < last; s += DEPTH_LANES) {
    uint n = min((uint)DEPTH_LANES, last - s);
    for (uint l = 0; l < n; ++l) {
      uint p = s + l;
      float x = position[3 * p], y = position[3 * p + 1], z = position[3 * p + 2];
      float d = view_depth(x, y, z, ex, ey, ez, fx, fy, fz);
      int receives = receives_shadows(x, y, z, nrm[4 * p + 3]);
      lo[l] = receives ? fmin(lo[l], d) : lo[l];
      hi[l] = receives ? fmax(hi[l], d) : hi[l];
    }
  }
  partials[get_global_id(0)] = min_max_halving(lo, hi, DEPTH_LANES);
}

// ---- GPU shape (issue 42): a work-group per chunk instead of a work-item; the work-items read
// pixels GROUP apart (adjacent work-items, adjacent pixels), then reduce in local memory.
// Minima, maxima and integer counts are exact in any order, so the results are the CPU
// shape's. ----

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif

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
