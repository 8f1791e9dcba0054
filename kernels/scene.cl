// Scene validation and bounds: every vertex and index is looked at here, once per upload.
// Work-item = one chunk of one mesh (the host's chunk table never lets a chunk span meshes).

typedef struct {
  uint first;  // first element (vertex or index) of the chunk in the scene-wide array
  uint count;
  uint limit;  // check_indices: the mesh's vertex count
  uint mesh;   // host bookkeeping
} chunk_t;

// Per chunk: the bounding box of its vertices (xyz min, xyz max) and the first vertex with a
// non-finite coordinate (-1 if none).
kernel void chunk_bounds(global const float* positions, global const chunk_t* chunks,
                         uint chunk_count, global float* boxes, global int* first_bad) {
  uint c = get_global_id(0);
  if (c >= chunk_count) return;
  float3 lo = (float3)(INFINITY), hi = (float3)(-INFINITY);
  int bad = -1;
  uint end = chunks[c].first + chunks[c].count;
  for (uint v = chunks[c].first; v < end; ++v) {
    float3 p = vload3(v, positions);
    if (bad < 0 && !(isfinite(p.x) && isfinite(p.y) && isfinite(p.z))) bad = (int)v;
    lo = fmin(lo, p);
    hi = fmax(hi, p);
  }
  vstore3(lo, 2 * c, boxes);
  vstore3(hi, 2 * c + 1, boxes);
  first_bad[c] = bad;
}

// Per chunk: the first index that does not name a vertex of its mesh (-1 if none).
kernel void check_indices(global const uint* indices, global const chunk_t* chunks,
                          uint chunk_count, global int* first_bad) {
  uint c = get_global_id(0);
  if (c >= chunk_count) return;
  int bad = -1;
  uint end = chunks[c].first + chunks[c].count;
  for (uint i = chunks[c].first; i < end && bad < 0; ++i)
    if (indices[i] >= chunks[c].limit) bad = (int)i;
  first_bad[c] = bad;
}
