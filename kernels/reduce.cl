// Reductions over the camera view (PSM near-plane push, Kozlov 14.1.2 / the paper §6), and the
// quality goals' samples of it.
//
// view_depth_partials: the min and max view depth (distance along the camera's forward axis)
// over the pixels that receive shadows (G-buffer normal.w != 0, position not NaN). One work-item
// reduces one chunk of pixels to one partial (min, max); +inf / -inf where a chunk has none. The
// host combines the few hundred partials. No barriers, no atomics (slow on a CPU device).
// Within a chunk, DEPTH_LANES running minima and maxima, halved into one at the end
// (min_max_halving): one running pair made every pixel wait for the last.

#include "reduce_common.cl"

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
