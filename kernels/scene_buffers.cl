// Scene validation and bounds: every vertex and index is looked at here, once per upload.
// Work-group = one chunk of one mesh (the host's chunk table never lets a chunk span meshes): one
// work-item on the CPU shape, GROUP (the profile's, as -DGROUP) on the GPU shape (issue 42), whose
// work-items take every GROUP-th element and then reduce in local memory. Minima, maxima and the
// first bad element are exact in any order: both shapes give the same results.
#ifndef GROUP
#define GROUP 1
#endif

typedef struct {
  uint first;  // first element (vertex or index) of the chunk in the scene-wide array
  uint count;
  uint limit;  // check_indices: the mesh's vertex count
  uint mesh;   // host bookkeeping
} chunk_t;

// Per chunk: the bounding box of its vertices (xyz min, xyz max) and the first vertex with a
// non-finite coordinate (-1 if none).
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void chunk_bounds(
    global const float* positions, global const chunk_t* chunks, uint chunk_count,
    global float* boxes, global int* first_bad) {
  local float lo[3][GROUP], hi[3][GROUP];
  local uint bad[GROUP];
  uint lid = get_local_id(0), c = get_global_id(0) / GROUP;
  if (c >= chunk_count) return;  // uniform over the work-group
  float3 l = (float3)(INFINITY), h = (float3)(-INFINITY);
  uint b = UINT_MAX;
  uint end = chunks[c].first + chunks[c].count;
  for (uint v = chunks[c].first + lid; v < end; v += GROUP) {
    float3 p = vload3(v, positions);
    if (b == UINT_MAX && !(isfinite(p.x) && isfinite(p.y) && isfinite(p.z))) b = v;
    l = fmin(l, p);
    h = fmax(h, p);
  }
  lo[0][lid] = l.x, lo[1][lid] = l.y, lo[2][lid] = l.z;
  hi[0][lid] = h.x, hi[1][lid] = h.y, hi[2][lid] = h.z;
  bad[lid] = b;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) {
      for (int a = 0; a < 3; ++a) {
        lo[a][lid] = fmin(lo[a][lid], lo[a][lid + span]);
        hi[a][lid] = fmax(hi[a][lid], hi[a][lid + span]);
      }
      bad[lid] = min(bad[lid], bad[lid + span]);
    }
  }
  if (lid != 0) return;
  vstore3((float3)(lo[0][0], lo[1][0], lo[2][0]), 2 * c, boxes);
  vstore3((float3)(hi[0][0], hi[1][0], hi[2][0]), 2 * c + 1, boxes);
  first_bad[c] = bad[0] == UINT_MAX ? -1 : (int)bad[0];
}

// Per chunk: the first index that does not name a vertex of its mesh (-1 if none).
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void check_indices(
    global const uint* indices, global const chunk_t* chunks, uint chunk_count,
    global int* first_bad) {
  local uint bad[GROUP];
  uint lid = get_local_id(0), c = get_global_id(0) / GROUP;
  if (c >= chunk_count) return;
  uint b = UINT_MAX;
  uint end = chunks[c].first + chunks[c].count;
  for (uint i = chunks[c].first + lid; i < end && b == UINT_MAX; i += GROUP)
    if (indices[i] >= chunks[c].limit) b = i;
  bad[lid] = b;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) bad[lid] = min(bad[lid], bad[lid + span]);
  }
  if (lid == 0) first_bad[c] = bad[0] == UINT_MAX ? -1 : (int)bad[0];
}
