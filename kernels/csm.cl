// Convolution shadow maps (Annen et al. 2007; blocker average: Annen et al. 2008, seed 004 §2.2
// and its Appendix). The occlusion test H(d - z) (1 where the map's depth z is nearer than the
// receiver's d) is expanded in the odd Fourier series of a square wave of period 2,
//   H(d - z) ~ 1/2 + 2 sum_k sin(c_k (d - z)) / c_k,   c_k = pi (2k - 1), k = 1..M,
// and sin(c (d - z)) = sin(c d) cos(c z) - cos(c d) sin(c z), so the test is linear in the basis
// images sin(c_k z), cos(c_k z) of the map: they can be prefiltered (mips) once and any window's
// occluded fraction read back in O(M). With z sin(c_k z), z cos(c_k z) and z as well, the same
// window gives the occluders' depth-weighted mass, and their average depth (seed eq. 7; the
// seed's "w_avg * pi/2" term is a typo for (w_avg * z) / 2):
//   z_avg = [ (w*z)/2 + 2 sum_k (sin(c_k d) (w*z cos) - cos(c_k d) (w*z sin)) / c_k ] / occluded.
//
// Depth: the map's depth is mapped linearly to [0, 1] between its near and far planes
// (orthographic: z as stored; perspective (spot, cube faces, PSM's point light in
// post-perspective space) z_ndc = alpha + beta / d -> (d - d_near) / (d_far - d_near); empty
// texels (z_ndc = 1) map to 1). Warped maps (PSM's orthographic and inverted ones, LiSPSM) have
// no such plane: their z_ndc, monotone with distance, is taken as stored. The basis takes half
// of it, z = linear / 2 in [0, 1/2]: then d - z stays in [-1/2, 1/2], half a period away
// from the square wave's other jumps at +-1. With z in [0, 1], a receiver at the far plane behind
// a caster at the near plane (d - z = 1) would read half lit.
//
// Storage: one buffer per channel family (sin, cos, z sin, z cos, z), each [texel][M] interleaved
// (z: one channel), level 0 then its mip levels back to back (mip_pyramid.cl). A family stays below
// 2 GiB at M = 16 up to 4096^2 even in float32. CSM_HALF stores half floats (vstore_half,
// round to nearest even) and reads them with vload_half; arithmetic is float throughout.

#ifdef CSM_HALF
typedef half basis_t;
#define BASIS_LOAD(p, i) vload_half((i), (p))
#define BASIS_STORE(v, p, i) vstore_half((v), (i), (p))
#else
typedef float basis_t;
#define BASIS_LOAD(p, i) ((p)[i])
#define BASIS_STORE(v, p, i) ((p)[i] = (v))
#endif

#define CSM_MAX_TERMS 16
// The GPU shape (engine/passes/pixel_shape.hpp) builds these same kernels with -DPIXEL_CHUNK=1
// -DGROUP_SIZE=<the profile's>: a work-item per texel and per pixel, each one's arithmetic as here.
#ifdef PIXEL_CHUNK
#define CSM_TEXEL_CHUNK PIXEL_CHUNK
#define CSM_PIXEL_CHUNK PIXEL_CHUNK
#else
#define CSM_TEXEL_CHUNK 256
#define CSM_PIXEL_CHUNK 64
#endif
#ifndef GROUP_SIZE
#define GROUP_SIZE 1
#endif
#define CSM_PI 3.14159265358979f
#define CSM_RANGE 0.5f  // the basis' depth: linear depth times this

// How the map's NDC z becomes linear depth in [0, 1] (csm_depth_t on the host: CsmDepthItem).
typedef struct {
  int perspective;          // z_ndc = alpha + beta / d (else z_ndc as it is)
  float alpha, beta;        //
  float d_near, inv_range;  // d at z_ndc = 0, 1 / (d_far - d_near)
  uint pad[3];
} csm_depth_t;

inline float csm_linear(float z_ndc, const csm_depth_t* m) {
  if (!m->perspective) return clamp(z_ndc, 0.0f, 1.0f);
  if (z_ndc >= 1.0f) return 1.0f;
  float d = m->beta / (z_ndc - m->alpha);
  return clamp((d - m->d_near) * m->inv_range, 0.0f, 1.0f);
}

// sin(pi z), cos(pi z) for z in [-1/2, 1/2] (x in [-pi/2, pi/2], no range reduction): Taylor
// polynomials to x^11 / x^12, error < 4e-7, and several times cheaper than sincos here.
inline float csm_sincospi(float z, float* c) {
  float x = CSM_PI * z, x2 = x * x;
  *c = 1.0f - x2 * 0.5f *
                  (1.0f - x2 * (1.0f / 12.0f) *
                              (1.0f - x2 * (1.0f / 30.0f) *
                                          (1.0f - x2 * (1.0f / 56.0f) *
                                                      (1.0f - x2 * (1.0f / 90.0f) *
                                                                  (1.0f - x2 * (1.0f / 132.0f))))));
  return x * (1.0f - x2 * (1.0f / 6.0f) *
                         (1.0f - x2 * (1.0f / 20.0f) *
                                     (1.0f - x2 * (1.0f / 42.0f) *
                                                 (1.0f - x2 * (1.0f / 72.0f) *
                                                             (1.0f - x2 * (1.0f / 110.0f))))));
}

// One work-item per CSM_TEXEL_CHUNK texels. `blocker` != 0 writes z sin, z cos and z too.
// sin/cos of c_k z by the rotation recurrence from sincos(pi z) and sincos(2 pi z): M steps of
// float rounding (~1e-6 at M = 16), far cheaper than M sincos calls.
__attribute__((reqd_work_group_size(GROUP_SIZE, 1, 1))) kernel void csm_basis(
    global const float* map, uint texels, csm_depth_t mapping, uint terms, int blocker,
    global basis_t* sin_out, global basis_t* cos_out, global basis_t* zsin_out,
    global basis_t* zcos_out, global basis_t* z_out) {
  uint first = get_global_id(0) * CSM_TEXEL_CHUNK;
  uint last = min(first + CSM_TEXEL_CHUNK, texels);
  for (uint t = first; t < last; ++t) {
    float z = CSM_RANGE * csm_linear(map[t], &mapping);
    float c1, s1 = csm_sincospi(z, &c1);
    float s2 = 2.0f * s1 * c1, c2 = c1 * c1 - s1 * s1;  // of 2 pi z
    float s = s1, c = c1;
    size_t base = (size_t)t * terms;
    for (uint k = 0; k < terms; ++k) {
      BASIS_STORE(s, sin_out, base + k);
      BASIS_STORE(c, cos_out, base + k);
      if (blocker) {
        BASIS_STORE(z * s, zsin_out, base + k);
        BASIS_STORE(z * c, zcos_out, base + k);
      }
      float sn = s * c2 + c * s2;  // sin((c_k + 2 pi) z)
      c = c * c2 - s * s2;
      s = sn;
    }
    if (blocker) BASIS_STORE(z, z_out, t);
  }
}

// The lookups take a family's mip chain as its buffer plus, per level l (level 0 = the basis),
// dims[l] = (w, h) and offsets[l], its first texel (times the family's channels).

// Adds `wt` times channels [0, n) of level `l` sampled bilinearly at (u, v) in [0, 1] (texel
// centres at (i + 0.5) / w, edges clamped) to acc.
inline void csm_bilinear(global const basis_t* b, uint n, global const uint2* dims,
                         global const ulong* offsets, uint l, float u, float v, float wt,
                         float* acc) {
  uint2 wh = dims[l];
  float x = u * wh.x - 0.5f, y = v * wh.y - 0.5f;
  float fx = floor(x), fy = floor(y);
  float ax = x - fx, ay = y - fy;
  int i0 = clamp((int)fx, 0, (int)wh.x - 1), i1 = clamp((int)fx + 1, 0, (int)wh.x - 1);
  int j0 = clamp((int)fy, 0, (int)wh.y - 1), j1 = clamp((int)fy + 1, 0, (int)wh.y - 1);
  size_t o = offsets[l];
  size_t t00 = (o + (size_t)j0 * wh.x + i0) * n, t10 = (o + (size_t)j0 * wh.x + i1) * n;
  size_t t01 = (o + (size_t)j1 * wh.x + i0) * n, t11 = (o + (size_t)j1 * wh.x + i1) * n;
  float w00 = wt * (1 - ax) * (1 - ay), w10 = wt * ax * (1 - ay);
  float w01 = wt * (1 - ax) * ay, w11 = wt * ax * ay;
  for (uint k = 0; k < n; ++k)
    acc[k] += w00 * BASIS_LOAD(b, t00 + k) + w10 * BASIS_LOAD(b, t10 + k) +
              w01 * BASIS_LOAD(b, t01 + k) + w11 * BASIS_LOAD(b, t11 + k);
}

// Trilinear: level lod in [0, levels - 1] (levels counts level 0), blended between the two
// levels around it; acc is zeroed first.
inline void csm_sample(global const basis_t* b, uint n, global const uint2* dims,
                       global const ulong* offsets, uint levels, float u, float v, float lod,
                       float* acc) {
  for (uint k = 0; k < n; ++k) acc[k] = 0.0f;
  lod = clamp(lod, 0.0f, (float)(levels - 1));
  uint l0 = (uint)lod;
  float f = lod - (float)l0;
  csm_bilinear(b, n, dims, offsets, l0, u, v, 1.0f - f, acc);
  if (f > 0.0f && l0 + 1 < levels) csm_bilinear(b, n, dims, offsets, l0 + 1, u, v, f, acc);
}

// What the lookups read over a window of `win` texels around (u, v): the families' mip chains,
// trilinearly at level log2 win, or with -DCSM_SAT their summed-area tables (summed_area.cl:
// doubles, [texel][n] interleaved, level 0's size in dims[0]), as a box of the texels whose centres
// lie within win / 2 of the point along each axis (at least the texel holding it), clipped to the
// map. At a level-l texel centre with win = 2^l both read the same aligned block.
#ifdef CSM_SAT
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double table_t;
inline void csm_fetch(global const double* t, uint n, global const uint2* dims,
                      global const ulong* offsets, uint levels, float u, float v, float win,
                      float* acc) {
  int2 wh = convert_int2(dims[0]);
  float x = u * wh.x, y = v * wh.y, r = 0.5f * win;
  int x0 = clamp((int)floor(x - r + 0.5f), 0, wh.x - 1),
      x1 = clamp((int)floor(x + r - 0.5f), 0, wh.x - 1);
  int y0 = clamp((int)floor(y - r + 0.5f), 0, wh.y - 1),
      y1 = clamp((int)floor(y + r - 0.5f), 0, wh.y - 1);
  x1 = max(x0, x1), y1 = max(y0, y1);
  double inv = 1.0 / ((double)(x1 - x0 + 1) * (double)(y1 - y0 + 1));
  size_t t11 = ((size_t)y1 * wh.x + x1) * n, t01 = ((size_t)y1 * wh.x + x0 - 1) * n;
  size_t t10 = ((size_t)(y0 - 1) * wh.x + x1) * n, t00 = ((size_t)(y0 - 1) * wh.x + x0 - 1) * n;
  for (uint k = 0; k < n; ++k) {
    double s = t[t11 + k];
    if (x0 > 0) s -= t[t01 + k];
    if (y0 > 0) s -= t[t10 + k];
    if (x0 > 0 && y0 > 0) s += t[t00 + k];
    acc[k] = (float)(s * inv);
  }
}
#else
typedef basis_t table_t;
inline void csm_fetch(global const basis_t* b, uint n, global const uint2* dims,
                      global const ulong* offsets, uint levels, float u, float v, float win,
                      float* acc) {
  csm_sample(b, n, dims, offsets, levels, u, v, portable_log2(win), acc);
}
#endif

// Ringing controls (csm_controls_t on the host: CsmControlsItem).
typedef struct {
  float damping;       // coefficient k is multiplied by exp(-damping (k / M)^2); 0 = none
  float depth_offset;  // the receiver's linear depth moves this much towards the light first
  float scale;         // visibility = clamp(1/2 + scale (v - 1/2), 0, 1); 1 = none
  float min_occluded;  // below this occluded fraction a window has no blocker
} csm_controls_t;

// Series weights 2 sigma_k / c_k.
inline void csm_weights(uint terms, float damping, float* w) {
  for (uint k = 0; k < terms; ++k) {
    float r = (float)(k + 1) / (float)terms;
    w[k] = 2.0f * portable_exp(-damping * r * r) / (CSM_PI * (float)(2 * k + 1));
  }
}

// sum_k w_k (sin(c_k d) C_k - cos(c_k d) S_k), with sin/cos(c_k d) by the same recurrence as the
// basis. d in [-1/4, 1/2] (csm_receiver).
inline float csm_series(uint terms, const float* w, float d, const float* S, const float* C) {
  float c1, s1 = csm_sincospi(d, &c1);
  float s2 = 2.0f * s1 * c1, c2 = c1 * c1 - s1 * s1;
  float s = s1, c = c1, sum = 0.0f;
  for (uint k = 0; k < terms; ++k) {
    sum += w[k] * (s * C[k] - c * S[k]);
    float sn = s * c2 + c * s2;
    c = c * c2 - s * s2;
    s = sn;
  }
  return sum;
}

// The occluded fraction of receiver depth d over a window of `win` texels, before the
// controls' clamp.
inline float csm_raw_occluded(global const table_t* sin_b, global const table_t* cos_b, uint terms,
                              global const uint2* dims, global const ulong* offsets, uint levels,
                              float u, float v, float win, float d, const float* w) {
  float S[CSM_MAX_TERMS], C[CSM_MAX_TERMS];
  csm_fetch(sin_b, terms, dims, offsets, levels, u, v, win, S);
  csm_fetch(cos_b, terms, dims, offsets, levels, u, v, win, C);
  return 0.5f + csm_series(terms, w, d, S, C);
}

// The receiver's depth in basis units: linear depth minus the offset, halved, and kept in
// [-1/4, 1/2] so that d - z stays in [-3/4, 1/2], away from the series' wrap at -1 (below 0 it
// is in front of every texel anyway).
inline float csm_receiver(float linear, float offset) {
  return clamp(CSM_RANGE * (linear - offset), -0.25f, 0.5f);
}

inline float csm_visibility_from(float occluded, const csm_controls_t* ctl) {
  return clamp(0.5f + ctl->scale * (0.5f - occluded), 0.0f, 1.0f);
}

// The average linear depth of the occluders of d in the window, and their fraction; where that
// fraction is below min_occluded there is no blocker: *occluded_out = 0 and the result is d
// itself (a penumbra of width 0). Clamped to [0, d] (d to [0, 1]): ringing can throw the ratio
// out.
inline float csm_blocker(global const table_t* sin_b, global const table_t* cos_b,
                         global const table_t* zsin_b, global const table_t* zcos_b,
                         global const table_t* z_b, uint terms, global const uint2* dims,
                         global const ulong* offsets, uint levels, float u, float v, float win,
                         float d, const float* w, float min_occluded, float* occluded_out) {
  float S[CSM_MAX_TERMS], C[CSM_MAX_TERMS], Z[1];
  csm_fetch(sin_b, terms, dims, offsets, levels, u, v, win, S);
  csm_fetch(cos_b, terms, dims, offsets, levels, u, v, win, C);
  float occluded = 0.5f + csm_series(terms, w, d, S, C);
  csm_fetch(zsin_b, terms, dims, offsets, levels, u, v, win, S);
  csm_fetch(zcos_b, terms, dims, offsets, levels, u, v, win, C);
  csm_fetch(z_b, 1, dims, offsets, levels, u, v, win, Z);
  float mass = 0.5f * Z[0] + csm_series(terms, w, d, S, C);
  float top = clamp(d, 0.0f, 1.0f);  // d may sit below 0 after the depth offset
  if (!(occluded > min_occluded)) {
    *occluded_out = 0.0f;
    return top;
  }
  *occluded_out = occluded;
  float z = mass / occluded;
  return isfinite(z) ? clamp(z, 0.0f, top) : top;
}

// Lookups at given points, for tests and probes: point = (u, v, window in texels, d) with d the
// receiver's
// linear [0, 1] depth (the depth offset is applied here as in csm_visibility). out = (visibility
// after the controls, raw occluded fraction, blocker average in linear [0, 1] depth, blocker
// occluded fraction); the blocker fields only when `blocker`.
__attribute__((reqd_work_group_size(GROUP_SIZE, 1, 1))) kernel void csm_probe(
    global const float4* points, uint count, global const table_t* sin_b,
    global const table_t* cos_b, global const table_t* zsin_b, global const table_t* zcos_b,
    global const table_t* z_b, uint terms, global const uint2* dims, global const ulong* offsets,
    uint levels, csm_controls_t ctl, int blocker, global float4* out) {
  uint first = get_global_id(0) * CSM_PIXEL_CHUNK;
  uint last = min(first + CSM_PIXEL_CHUNK, count);
  float w[CSM_MAX_TERMS];
  csm_weights(terms, ctl.damping, w);
  for (uint p = first; p < last; ++p) {
    float4 q = points[p];
    float d = csm_receiver(q.w, ctl.depth_offset);
    float occ = csm_raw_occluded(sin_b, cos_b, terms, dims, offsets, levels, q.x, q.y, q.z, d, w);
    float4 r = (float4)(csm_visibility_from(occ, &ctl), occ, NAN, NAN);
    if (blocker) {
      float bo;
      r.z = csm_blocker(sin_b, cos_b, zsin_b, zcos_b, z_b, terms, dims, offsets, levels, q.x, q.y,
                        q.z, d, w, ctl.min_occluded, &bo);
      r.z /= CSM_RANGE;
      r.w = bo;
    }
    out[p] = r;
  }
}

#define CSM_MODE_FIXED 0  // FILTER_CSM: one window of `window` texels
#define CSM_MODE_PCSS 1   // FILTER_PCSS_CSM: blocker window -> penumbra -> filtered test

// Per camera pixel (as pcss.cl): visibility, and the blocker average in linear [0, 1] depth
// when `blocker_out` is asked for (want_blocker). FIXED: the CSM test over a window of `window`
// texels; the blocker average over the same window. PCSS: the blocker
// window is PCSS's search region (light size, near plane, receiver depth), the penumbra
// (seed eq. 2, pcss.cl's similar triangles) gives the test's window. The receiver plane's depth
// change across half the window (its slope per texel from the normal) is taken off d besides
// the NDC biases and the controls' depth offset: one d stands for the whole window. A cube
// face (-DCUBE_FACES) writes only the pixels it owns. PCSS mode needs the light's own
// projection (uniform maps).
__attribute__((reqd_work_group_size(GROUP_SIZE, 1, 1))) kernel void csm_visibility(
    global const float* position, global const float4* normal, uint pixel_count,
    shadow_lookup_t lookup, faces_t faces, csm_depth_t mapping, global const table_t* sin_b,
    global const table_t* cos_b, global const table_t* zsin_b, global const table_t* zcos_b,
    global const table_t* z_b, uint terms, global const uint2* dims, global const ulong* offsets,
    uint levels, csm_controls_t ctl, int mode, float window, float size, float2 scale,
    int want_blocker, global float* visibility, global float* blocker_out) {
  uint first = get_global_id(0) * CSM_PIXEL_CHUNK;
  uint last = min(first + CSM_PIXEL_CHUNK, pixel_count);
  float16 to_ndc = lookup.to_ndc;
  float map_size = (float)lookup.map_size;
  float w[CSM_MAX_TERMS];
  csm_weights(terms, ctl.damping, w);
  float tex = fmax(scale.x, scale.y);  // texels per light unit (the mips are isotropic)
  float range = 1.0f / mapping.inv_range;
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    if (!owns_pixel(&faces, x.x, x.y, x.z)) continue;
    float4 n = normal[p];
    float4 c = mul_m4(to_ndc, (float4)(x, 1.0f));
    float3 s = c.xyz / c.w;
    // Where nothing occludes (or nothing is looked up) the blocker is the point's own depth.
    float vis = 1.0f, blk = c.w > 0.0f ? csm_linear(s.z, &mapping) : 0.0f;
    float above = 1.0f;  // a receiver's share of the light's disk above its horizon
    if (isnan(x.x)) {
      vis = blk = NAN;
    } else if (outside_spot_cone(x, &lookup.light)) {
      vis = 0.0f;
    } else if (n.w != 0.0f && (above = disk_above_horizon(x, n.xyz, &lookup.light)) == 0.0f) {
      vis = 0.0f;
    } else if (n.w != 0.0f) {
      if (c.w > 0.0f && s.x >= 0.0f && s.y >= 0.0f && s.x < 1.0f && s.y < 1.0f) {
        float2 g = depth_gradient(to_ndc, n.xyz, c, map_size);
        float slope =
            isfinite(g.x) && isfinite(g.y) ? fmin(fabs(g.x) + fabs(g.y), MAX_SLOPE) : MAX_SLOPE;
        float zb = s.z - (lookup.bias_constant + lookup.bias_slope * slope);
        float dr = csm_linear(s.z, &mapping);  // the receiver, unbiased
        // Real linear depths for the penumbra: d_near + t * range (directional: range = 1).
        float real_r = mapping.d_near + dr * range;
        float win;
        if (mode == CSM_MODE_FIXED) {
          win = window;
        } else {
          // PCSS's search region (pcss.cl), as a window of texels.
          float search = mapping.perspective
                             ? size * (real_r - mapping.d_near) / real_r / mapping.d_near
                             : (real_r - mapping.d_near) * size;
          win = 2.0f * search * tex;
        }
        win = clamp(win, 1.0f, map_size);
        float d = csm_receiver(csm_linear(zb - slope * 0.5f * win, &mapping), ctl.depth_offset);
        float bo = 0.0f;
        if (mode == CSM_MODE_PCSS || want_blocker)
          blk = csm_blocker(sin_b, cos_b, zsin_b, zcos_b, z_b, terms, dims, offsets, levels, s.x,
                            s.y, win, d, w, ctl.min_occluded, &bo) /
                CSM_RANGE;
        if (bo == 0.0f) blk = dr;  // no blocker: the point's own depth
        if (mode == CSM_MODE_PCSS) {
          if (bo > 0.0f) {
            float real_b = mapping.d_near + blk * range;
            float half_w = mapping.perspective ? (real_r - real_b) * size / real_b / real_r
                                               : (real_r - real_b) * size;
            win = clamp(2.0f * half_w * tex, 1.0f, map_size);
            d = csm_receiver(csm_linear(zb - slope * 0.5f * win, &mapping), ctl.depth_offset);
            float occ =
                csm_raw_occluded(sin_b, cos_b, terms, dims, offsets, levels, s.x, s.y, win, d, w);
            vis = csm_visibility_from(occ, &ctl);
          }
        } else {
          float occ =
              csm_raw_occluded(sin_b, cos_b, terms, dims, offsets, levels, s.x, s.y, win, d, w);
          vis = csm_visibility_from(occ, &ctl);
        }
      }
    }
    visibility[p] = isnan(vis) ? vis : fmin(vis, above);
    if (want_blocker) blocker_out[p] = blk;
  }
}

// The basis as one float texture for readback (PRODUCT_CSM_BASIS): channels sin1..sinM,
// cos1..cosM and, with `blocker`, zsin1..zsinM, zcos1..zcosM, z, interleaved per texel.
__attribute__((reqd_work_group_size(GROUP_SIZE, 1, 1))) kernel void csm_pack(
    global const basis_t* sin_b, global const basis_t* cos_b, global const basis_t* zsin_b,
    global const basis_t* zcos_b, global const basis_t* z_b, uint texels, uint terms, int blocker,
    global float* out) {
  uint first = get_global_id(0) * CSM_TEXEL_CHUNK;
  uint last = min(first + CSM_TEXEL_CHUNK, texels);
  uint channels = blocker ? 4 * terms + 1 : 2 * terms;
  for (uint t = first; t < last; ++t) {
    global float* o = out + (size_t)t * channels;
    size_t b = (size_t)t * terms;
    for (uint k = 0; k < terms; ++k) {
      o[k] = BASIS_LOAD(sin_b, b + k);
      o[terms + k] = BASIS_LOAD(cos_b, b + k);
      if (blocker) {
        o[2 * terms + k] = BASIS_LOAD(zsin_b, b + k);
        o[3 * terms + k] = BASIS_LOAD(zcos_b, b + k);
      }
    }
    if (blocker) o[4 * terms] = BASIS_LOAD(z_b, t);
  }
}
