// Reductions over the camera view (PSM near-plane push, Kozlov 14.1.2 / the paper §6), and the
// quality goals' samples of it.
//
// view_depth_partials: the min and max view depth (distance along the camera's forward axis)
// over the pixels that receive shadows (G-buffer normal.w != 0, position not NaN). One work-item
// reduces one chunk of pixels to one partial (min, max); +inf / -inf where a chunk has none. The
// host combines the few hundred partials. No barriers, no atomics (slow on a CPU device).

#define DEPTH_CHUNK 4096

kernel void view_depth_partials(global const float* position, global const float4* normal,
                                uint pixel_count, float4 eye, float4 forward,
                                global float2* partials) {
  uint first = get_global_id(0) * DEPTH_CHUNK;
  uint last = min(first + DEPTH_CHUNK, pixel_count);
  float lo = INFINITY, hi = -INFINITY;
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    float w = normal[p].w;
    // NaN positions fail both comparisons through the depth; test them explicitly anyway.
    bool receives = !isnan(x.x) && !isnan(x.y) && !isnan(x.z) && w != 0.0f && !isnan(w);
    float d = dot(x - eye.xyz, forward.xyz);
    lo = receives ? fmin(lo, d) : lo;
    hi = receives ? fmax(hi, d) : hi;
  }
  partials[get_global_id(0)] = (float2)(lo, hi);
}

// boundary_cells: per cell of a columns x rows grid of equal cells (cell (c, r) holds the pixels
// x in [c width / columns, (c + 1) width / columns), likewise y), the pixels seen (visibility not
// NaN) and those of them on a shadow boundary: whose visibility differs by more than 0.5 from a
// seen 4-neighbour's. The quality goals' probe (engine/passes/boundary.hpp): the view's share,
// and where its edges lie, which weighs each grid sample's predicted error. One work-item per
// cell; the host sums them.
kernel void boundary_cells(global const float* visibility, uint width, uint height, uint columns,
                           uint rows, global uint2* cells) {
  uint i = get_global_id(0);
  if (i >= columns * rows) return;
  uint c = i % columns, r = i / columns;
  uint x0 = (uint)(((ulong)c * width) / columns), x1 = (uint)(((ulong)(c + 1) * width) / columns);
  uint y0 = (uint)(((ulong)r * height) / rows), y1 = (uint)(((ulong)(r + 1) * height) / rows);
  uint seen = 0, boundary = 0;
  for (uint y = y0; y < y1; ++y) {
    global const float* row = visibility + (size_t)y * width;
    global const float* up = y > 0 ? row - width : row;
    global const float* down = y + 1 < height ? row + width : row;
    for (uint x = x0; x < x1; ++x) {
      float v = row[x];
      if (isnan(v)) continue;
      float l = row[x > 0 ? x - 1 : x], rt = row[x + 1 < width ? x + 1 : x];
      // A neighbour off the image is the pixel itself; NaN neighbours fail the comparison.
      bool edge = fabs(v - l) > 0.5f || fabs(v - rt) > 0.5f || fabs(v - up[x]) > 0.5f ||
                  fabs(v - down[x]) > 0.5f;
      ++seen;
      boundary += edge;
    }
  }
  cells[i] = (uint2)(seen, boundary);
}

// view_samples: the camera view's surface at the centres of a columns x rows grid of equal cells
// (pixel ((2c + 1) width / (2 columns), (2r + 1) height / (2 rows))), for a quality goal's error
// prediction (engine/passes/view_samples.hpp): position (NaN where nothing is seen), then the
// normal where the pixel receives shadows, else 0. One work-item per sample.
kernel void view_samples(global const float* position, global const float4* normal, uint width,
                         uint height, uint columns, uint rows, global float8* samples) {
  uint i = get_global_id(0);
  if (i >= columns * rows) return;
  uint c = i % columns, r = i / columns;
  uint x = (uint)(((ulong)(2 * c + 1) * width) / (2 * (ulong)columns));
  uint y = (uint)(((ulong)(2 * r + 1) * height) / (2 * (ulong)rows));
  uint p = y * width + x;
  float3 at = vload3(p, position);
  float4 n = normal[p];
  bool receives = n.w != 0.0f && !isnan(n.w);
  float3 facing = receives ? n.xyz : (float3)(0.0f);
  samples[i] = (float8)(at, 0.0f, facing, 0.0f);
}

// edge_sampling_partials: per camera row, the pixels seen (not NaN) in `difference`, |hard -
// filtered| of two tests of the same map (pcf.cl, PCF_EDGE), and its sum over them. With the
// hard test and the bilinear 2x2 filter, the mean is the misclassified share edge sampling alone
// explains (a shadow edge lies anywhere between two texel centres): TECHNIQUE_AUTO's trial of its
// candidates (engine/passes/edge_sampling.hpp). The host sums the rows.
kernel void edge_sampling_partials(global const float* difference, uint width, uint height,
                                   global float2* partials) {
  uint y = get_global_id(0);
  if (y >= height) return;
  global const float* d = difference + (size_t)y * width;
  float seen = 0.0f, sum = 0.0f;
  for (uint x = 0; x < width; ++x) {
    bool is_seen = !isnan(d[x]);
    seen += is_seen ? 1.0f : 0.0f;
    sum += is_seen ? d[x] : 0.0f;
  }
  partials[y] = (float2)(seen, sum);
}
