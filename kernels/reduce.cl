// Reductions over the camera view (PSM near-plane push, Kozlov 14.1.2 / the paper §6), and the
// quality goals' samples of it.
//
// view_depth_partials: the min and max view depth (distance along the camera's forward axis)
// over the pixels that receive shadows (G-buffer normal.w != 0, position not NaN). One work-item
// reduces one chunk of pixels to one partial (min, max); +inf / -inf where a chunk has none. The
// host combines the few hundred partials. No barriers, no atomics (slow on a CPU device).
// Within a chunk, DEPTH_LANES running minima and maxima, halved into one at the end
// (min_max_halving): one running pair made every pixel wait for the last.

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
        float v = row[x];
        // A neighbour off the image is the pixel itself; NaN neighbours fail the comparison.
        float left = row[x > 0 ? x - 1 : x], right = row[x + 1 < width ? x + 1 : x];
        uint m = (fabs(v - left) > 0.5f ? 1u : 0u) | (fabs(v - right) > 0.5f ? 2u : 0u) |
                 (fabs(v - up[x]) > 0.5f ? 4u : 0u) | (fabs(v - down[x]) > 0.5f ? 8u : 0u);
        bool is_seen = !isnan(v);
        seen += is_seen ? 1u : 0u;
        changes[l] = is_seen ? (uchar)m : (uchar)0;
        any |= m;
      }
      if (!any) continue;  // the common case: no change in this chunk
      for (uint l = 0; l < n; ++l) {
        uint m = changes[l];
        if (!m) continue;
        uint x = first + l, p = y * width + x;
        surface_t s = pixel_surface(position, normal, p, eye, &light);
        if (!s.lit) continue;
        uint q[4] = {x > 0 ? p - 1 : p, x + 1 < width ? p + 1 : p, y > 0 ? p - width : p,
                     y + 1 < height ? p + width : p};
        bool edge = false;
        for (uint k = 0; k < 4; ++k)
          edge = edge || ((m >> k & 1u) && on_lit_surface(&s, position, normal, q[k], &light));
        boundary += edge;
      }
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
