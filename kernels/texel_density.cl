// Perspective aliasing per camera pixel: the size in pixels of one shadow-map texel's footprint
// on the visible surface (> 1: the map under-samples there). NaN where the camera sees nothing
// or the point lies outside the map. A cube (-DCUBE_FACES) is one launch: each pixel reads the
// matrix of its face, and a face not rendered has a zero matrix (outside: NaN).
//
// On the surface's tangent plane, J_light maps a tangent step to map texels and J_camera to
// image pixels (both the exact derivative of a projective map, as in the shadow test's slope
// bias). A = J_camera * inverse(J_light) maps a texel step to pixels; its larger singular value
// is the length of the texel's longest footprint axis in pixels.
//
// Layout for PoCL's CPU backend, as pcf.cl's: one work-item per strip of 64 pixels, every loop
// over the strip's lanes in scalar floats without branches (cases computed and selected), so
// that LLVM vectorizes them. One pixel at a time with float3 values, branches and hypot ran
// 9-14x slower (docs/benchmarks.md).

// The GPU shape (engine/passes/pixel_shape.hpp) builds this same kernel with -DPIXEL_CHUNK=1
// -DGROUP_SIZE=<the profile's>: a work-item per pixel, each pixel's arithmetic and bits as here.
#ifndef PIXEL_CHUNK
#define PIXEL_CHUNK 64
#endif
#ifndef GROUP_SIZE
#define GROUP_SIZE 1
#endif

// sqrt(u^2 + v^2) without overflow where u^2 would (hypot, which does not vectorize here).
inline float length2(float u, float v) {
  float a = fabs(u), b = fabs(v);
  float big = fmax(a, b), r = fmin(a, b) / big;
  return big > 0.0f ? big * sqrt(1.0f + r * r) : 0.0f;
}

// d(ndc.xy) / dt for tangent t at point c = M * (p, 1), scaled to texels or pixels: the x and y
// of M * (t, 0) as mx, my and its w as mw.
#define NDC_STEP(mx, my, mw, cx, cy, cw, scale_x, scale_y, out_x, out_y) \
  {                                                                      \
    float inv_w_ = 1.0f / (cw);                                          \
    out_x = ((mx) - (cx)*inv_w_ * (mw)) * inv_w_ * (scale_x);            \
    out_y = ((my) - (cy)*inv_w_ * (mw)) * inv_w_ * (scale_y);            \
  }

// The footprint of every lane in `use` of the strip through light matrix `m` into `out`.
inline void strip_density(float16 m, float16 c, const float* px, const float* py, const float* pz,
                          const float* nx, const float* ny, const float* nz, const uint* use,
                          float texels, float width, float height, float* out) {
  for (uint l = 0; l < PIXEL_CHUNK; ++l) {
    float x = px[l], y = py[l], z = pz[l];
    float lx = m.s0 * x + m.s4 * y + m.s8 * z + m.sc;
    float ly = m.s1 * x + m.s5 * y + m.s9 * z + m.sd;
    float lw = m.s3 * x + m.s7 * y + m.sb * z + m.sf;
    float sx = lx / lw, sy = ly / lw;
    int inside = (x == x) & (lw > 0.0f) & (sx >= 0.0f) & (sy >= 0.0f) & (sx < 1.0f) & (sy < 1.0f);
    // t1 = normalize(n x (1, 0, 0)) or normalize(n x (0, 1, 0)); t2 = n x t1.
    float n0 = nx[l], n1 = ny[l], n2 = nz[l];
    int about_x = fabs(n0) < 0.9f;
    float t0 = about_x ? 0.0f : -n2, t1 = about_x ? n2 : 0.0f, t2 = about_x ? -n1 : n0;
    float inv = 1.0f / sqrt(t0 * t0 + t1 * t1 + t2 * t2);
    t0 *= inv, t1 *= inv, t2 *= inv;
    float u0 = n1 * t2 - n2 * t1, u1 = n2 * t0 - n0 * t2, u2 = n0 * t1 - n1 * t0;
    float cx = c.s0 * x + c.s4 * y + c.s8 * z + c.sc;
    float cy = c.s1 * x + c.s5 * y + c.s9 * z + c.sd;
    float cw = c.s3 * x + c.s7 * y + c.sb * z + c.sf;
    float l1x, l1y, l2x, l2y, c1x, c1y, c2x, c2y;
    NDC_STEP(m.s0 * t0 + m.s4 * t1 + m.s8 * t2, m.s1 * t0 + m.s5 * t1 + m.s9 * t2,
             m.s3 * t0 + m.s7 * t1 + m.sb * t2, lx, ly, lw, texels, texels, l1x, l1y)
    NDC_STEP(m.s0 * u0 + m.s4 * u1 + m.s8 * u2, m.s1 * u0 + m.s5 * u1 + m.s9 * u2,
             m.s3 * u0 + m.s7 * u1 + m.sb * u2, lx, ly, lw, texels, texels, l2x, l2y)
    NDC_STEP(c.s0 * t0 + c.s4 * t1 + c.s8 * t2, c.s1 * t0 + c.s5 * t1 + c.s9 * t2,
             c.s3 * t0 + c.s7 * t1 + c.sb * t2, cx, cy, cw, width, height, c1x, c1y)
    NDC_STEP(c.s0 * u0 + c.s4 * u1 + c.s8 * u2, c.s1 * u0 + c.s5 * u1 + c.s9 * u2,
             c.s3 * u0 + c.s7 * u1 + c.sb * u2, cx, cy, cw, width, height, c2x, c2y)
    float det = l1x * l2y - l2x * l1y;
    // inverse(J_light) = [l2.y, -l2.x; -l1.y, l1.x] / det; A = J_camera * that.
    float a1x = (c1x * l2y - c2x * l1y) / det, a1y = (c1y * l2y - c2y * l1y) / det;
    float a2x = (c2x * l1x - c1x * l2x) / det, a2y = (c2y * l1x - c1y * l2x) / det;
    // Largest singular value of [a1 a2] without the cancellation of the eigenvalue form.
    float f = 0.5f * (length2(a1x + a2y, a1y - a2x) + length2(a1x - a2y, a1y + a2x));
    f = det == 0.0f ? INFINITY : f;  // the light grazes the surface: a texel covers a line
    out[l] = use[l] ? (inside ? f : NAN) : out[l];
  }
}

__attribute__((reqd_work_group_size(GROUP_SIZE, 1, 1))) __attribute__((min_vector_width(512)))
kernel void
texel_density(global const float* position, global const float4* normal, uint pixel_count,
              float16 single_to_ndc, faces_t faces, cube_ndc_t cube, uint map_size,
              float16 camera_to_ndc, uint width, uint height, global float* density) {
  uint own = get_global_id(0) * PIXEL_CHUNK;  // this work-item writes [own, own + 64)
  if (own >= pixel_count) return;
  // The strip is [first, first + 64): the last one is shifted back over its neighbour so that
  // every lane is a real pixel; an image under 64 pixels pads its lanes with the sky (NaN).
  uint first = pixel_count >= PIXEL_CHUNK ? min(own, pixel_count - PIXEL_CHUNK) : 0;
  uint lanes = min((uint)PIXEL_CHUNK, pixel_count);
  float px[PIXEL_CHUNK], py[PIXEL_CHUNK], pz[PIXEL_CHUNK];
  float nx[PIXEL_CHUNK], ny[PIXEL_CHUNK], nz[PIXEL_CHUNK], out[PIXEL_CHUNK];
  uint use[PIXEL_CHUNK];
  global const float* nrm = (global const float*)normal;
  // De-interleaved by scalar loops: vectorized, the strided loads become slow gathers.
#pragma clang loop vectorize(disable)
  for (uint l = 0; l < PIXEL_CHUNK; ++l) {
    uint p = first + min(l, lanes - 1);
    px[l] = l < lanes ? position[3 * p] : NAN;
    py[l] = position[3 * p + 1];
    pz[l] = position[3 * p + 2];
  }
#pragma clang loop vectorize(disable)
  for (uint l = 0; l < PIXEL_CHUNK; ++l) {
    uint p = first + min(l, lanes - 1);
    nx[l] = nrm[4 * p], ny[l] = nrm[4 * p + 1], nz[l] = nrm[4 * p + 2];
    out[l] = NAN;
  }
  float texels = (float)map_size;
#ifdef CUBE_FACES
  // One pass per face among the strip's pixels, its matrix uniform across the lanes.
  uint face[PIXEL_CHUNK], present = 0;
  for (uint l = 0; l < PIXEL_CHUNK; ++l) {
    face[l] = cube_face(&faces, px[l], py[l], pz[l]);
    present |= px[l] != px[l] ? 0u : 1u << face[l];
  }
  for (uint f = 0; f < 6; ++f) {
    if (!(present & (1u << f))) continue;
    for (uint l = 0; l < PIXEL_CHUNK; ++l) use[l] = face[l] == f;
    strip_density(cube.to_ndc[f], camera_to_ndc, px, py, pz, nx, ny, nz, use, texels, (float)width,
                  (float)height, out);
  }
#else
  for (uint l = 0; l < PIXEL_CHUNK; ++l) use[l] = 1;
  strip_density(single_to_ndc, camera_to_ndc, px, py, pz, nx, ny, nz, use, texels, (float)width,
                (float)height, out);
#endif
  for (uint l = own - first; l < lanes; ++l) density[first + l] = out[l];
}
