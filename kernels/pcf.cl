// Percentage-closer filtering of the shadow test: the visibilities of several texels are averaged
// (never the depths). Bilinear 2x2 weighs the four texels around the point like a bilinear
// lookup; Poisson-disk PCF averages N taps within a radius, optionally rotated per pixel. Each
// tap compares the receiver plane's depth at that tap (the plane's gradient per texel), so wide
// kernels do not self-shadow tilted planes. PCF_NEAREST is the hard shadow test (one texel).
//
// Layout for PoCL's CPU backend: one work-item per strip of 64 pixels, and every loop runs over
// the 64 pixels of the strip without branches so that LLVM vectorizes it (checked with
// POCL_VECTORIZER_REMARKS=1): the set-up computes every case and selects, and the Poisson taps
// run with the tap loop outside and the pixel loop inside (gathers from the map). One pixel at a
// time with branches and the taps inside ran ~8x slower.

// The GPU shape (engine/passes/pixel_shape.hpp) builds this same kernel with -DPIXEL_CHUNK=1
// -DGROUP_SIZE=<the profile's>: a work-item per pixel, each pixel's arithmetic and bits as here.
#ifndef PIXEL_CHUNK
#define PIXEL_CHUNK 64
#endif
#ifndef GROUP_SIZE
#define GROUP_SIZE 1
#endif
#define PCF_BILINEAR 0
#define PCF_POISSON 1
// The hard shadow test (ShadowTestPass): the nearest texel, no filtering. It runs here for the
// vectorized set-up: a per-pixel loop with branches was 3x slower (docs/benchmarks.md).
#define PCF_NEAREST 2
// Both of the above at once, written as |hard - bilinear 2x2| (0 where neither filters, NaN where
// nothing is seen): TECHNIQUE_AUTO's trial (EdgeSamplingPass). One set-up and one write instead
// of two; each value is bit for bit that of the two modes run apart.
#define PCF_EDGE 3

// 1 lit, 0 shadowed; texels off the map are lit (the map covers every caster). Off-map texels
// load an edge texel instead of branching. Maps are <= 8192^2, so the index fits an int.
inline float texel_test(global const float* map, int size, int i, int j, float z) {
  int inside = ((uint)i < (uint)size) & ((uint)j < (uint)size);
  // Clamped rather than selected index: LLVM then keeps 32-bit gather indices (16 per gather).
  float m = map[min(max(j, 0), size - 1) * size + min(max(i, 0), size - 1)];
  return (!inside | (z <= m)) ? 1.0f : 0.0f;
}

// Virtual maps (issue 53), built with -DVIRTUAL: each pixel reads the clipmap level that marking
// gave it (pixel_level, virtual_pages.cl), and a level's texel lies on its page's slot of the pool
// (map0), found in the level's page table (rows of its texels / PAGE_TEXELS pages). A tap off the
// level's window or on a page without a slot is lit, as off a dense map: marking gave every tap's
// page a slot while the pool lasted.
#define PAGE_TEXELS 128
#define NO_PAGE 0xffffffffu
#define NO_LEVEL 0xff
inline float page_test(global const float* pool, global const uint* table, int size, int i, int j,
                       float z) {
  int inside = ((uint)i < (uint)size) & ((uint)j < (uint)size);
  int ci = min(max(i, 0), size - 1), cj = min(max(j, 0), size - 1);
  uint slot = table[(cj / PAGE_TEXELS) * (size / PAGE_TEXELS) + ci / PAGE_TEXELS];
  int resident = slot != NO_PAGE;
  float m = pool[(resident ? slot : 0u) * (PAGE_TEXELS * PAGE_TEXELS) +
                 (cj % PAGE_TEXELS) * PAGE_TEXELS + ci % PAGE_TEXELS];
  return (!inside | !resident | (z <= m)) ? 1.0f : 0.0f;
}
#ifdef VIRTUAL
#define TEXEL_TEST(i, j, z) page_test(map, table, size, i, j, z)
#else
#define TEXEL_TEST(i, j, z) texel_test(map, size, i, j, z)
#endif

// The loops below use scalar floats only: LLVM's loop vectorizer gives up on loops that hold
// OpenCL vector types (float3/float4 values) and on PoCL builtins with branches or calls.

// Interleaved gradient noise (Jimenez 2014): a rotation angle in [0, 2 pi) per pixel.
inline float pixel_angle(uint px, uint py) {
  float x = (float)px, y = (float)py;
  float a = 0.06711056f * x + 0.00583715f * y;
  a = 52.9829189f * (a - (float)floor_int(a));
  return 6.2831853f * (a - (float)floor_int(a));
}

// taylor_sin, taylor_cos: prelude.cl.

__attribute__((reqd_work_group_size(GROUP_SIZE, 1, 1))) __attribute__((min_vector_width(512)))
kernel void
pcf(global const float* position, global const float4* normal, uint pixel_count, uint width,
    shadow_lookup_t lookup, faces_t faces, cube_ndc_t cube, global const float* map0,
    global const float* map1, global const float* map2, global const float* map3,
    global const float* map4, global const float* map5, int mode, global const float2* taps,
    uint tap_count, float radius, int rotate, global float* visibility
#ifdef VIEW_DEPTH
    ,
    float4 eye, float4 forward, global float2* depth_partials
#endif
#ifdef VIRTUAL
    ,
    global const uint* page_table, global const float16* level_ndc, global const uint* level_texels,
    global const uchar* pixel_level
#endif
) {
  uint own = get_global_id(0) * PIXEL_CHUNK;  // this work-item writes [own, own + 64)
  if (own >= pixel_count) return;
  // The strip is [first, first + 64): the last one is shifted back over its neighbour so that
  // every lane is a real pixel (images under 64 pixels leave the spare lanes unfiltered).
  uint first = pixel_count >= PIXEL_CHUNK ? min(own, pixel_count - PIXEL_CHUNK) : 0;
  // The lookup's fields as locals, read once per work-item.
  uint map_size = lookup.map_size;
  float bias_constant = lookup.bias_constant, bias_slope = lookup.bias_slope;
  float4 light_position = lookup.light.position, light_axis = lookup.light.axis;
  float cos_half_cone = lookup.light.cos_half_cone;
  int light_kind = lookup.light.kind;
  // The direction away from the light at point p is travel + along * (p - light): a sun's
  // direction of travel, or p - light for a local light (facing away or edge-on: n . it >= 0).
  int directional = light_kind == LIGHT_DIRECTIONAL;
  float travel_x = directional ? light_axis.x : 0.0f, travel_y = directional ? light_axis.y : 0.0f;
  float travel_z = directional ? light_axis.z : 0.0f, along = directional ? 0.0f : 1.0f;
  global const float* nrm = (global const float*)normal;
  // Lanes past a small image's end stay unfiltered; elsewhere the index is affine in l, so the
  // loads below are unit-stride vector loads (a clamped index made each of them a gather).
  uint lanes = min((uint)PIXEL_CHUNK, pixel_count);
  // Positions de-interleaved by a scalar loop: vectorized, the stride-3 loads become gathers,
  // which are slow on this CPU.
  float px[PIXEL_CHUNK], py[PIXEL_CHUNK], pw[PIXEL_CHUNK];
#pragma clang loop vectorize(disable)
  for (uint l = 0; l < lanes; ++l) {
    px[l] = position[3 * (first + l)];
    py[l] = position[3 * (first + l) + 1];
    pw[l] = position[3 * (first + l) + 2];
  }
  // Each pixel's map: a cube face, a virtual map's level, or the single map (face 0). The strip
  // is set up and filtered once per face among its pixels: one face, or a few along a cube
  // face's edge or a level's. The face's matrix and map are then uniform: with them picked per
  // lane (selects and pointer gathers) the hard test of a cube took 5x as long.
#if defined(CUBE_FACES) || defined(VIRTUAL)
#define PER_FACE
  uint face[PIXEL_CHUNK], faces_present = 0;
  for (uint l = lanes; l < PIXEL_CHUNK; ++l) face[l] = 0;
  for (uint l = 0; l < lanes; ++l) {
#ifdef VIRTUAL
    uint level = pixel_level[first + l];  // NO_LEVEL: lit, set up with level 0 (off_map)
    face[l] = level == NO_LEVEL ? 0 : level;
#else
    face[l] = cube_face(&faces, px[l], py[l], pw[l]);
#endif
    faces_present |= isnan(px[l]) ? 0u : 1u << face[l];
  }
  // The strip's result: the sky's NaN until a face writes its pixels.
  float out[PIXEL_CHUNK];
  for (uint l = 0; l < PIXEL_CHUNK; ++l) out[l] = NAN;
#define IN_FACE(l, f) (face[l] == (f))
#else
  uint faces_present = 1;  // a single map decides every pixel: set up and filter once
#define IN_FACE(l, f) 1
#endif
  // Poisson's per-pixel rotation, whatever the face.
  float pcs[PIXEL_CHUNK], psn[PIXEL_CHUNK];
  if (mode == PCF_POISSON) {
    uint x0 = first % width, y0 = first / width;
#pragma clang loop vectorize_width(16)
    for (uint l = 0; l < PIXEL_CHUNK; ++l) {
      // The pixel's column and row without a division per lane (a strip spans <= 2 rows).
      uint px = x0 + l, py = y0;
      if (width >= PIXEL_CHUNK) {
        py += px >= width;
        px -= px >= width ? width : 0;
      } else {
        px = (first + l) % width, py = (first + l) / width;  // spare lanes: unused values
      }
      float h = 0.5f * pixel_angle(px, py) - 1.5707963f;
      float hs = taylor_sin(h, h * h), hc = taylor_cos(h * h);
      // radius folded in once per pixel (exact when not rotated: radius * 1 and radius * 0).
      psn[l] = rotate ? -2.0f * hs * hc * radius : 0.0f;
      pcs[l] = rotate ? (2.0f * hs * hs - 1.0f) * radius : radius;
    }
  }
  // Per pixel of the strip: the result where no filtering is needed (vis), else the set-up for
  // the filter.
  float vis[PIXEL_CHUNK], pu[PIXEL_CHUNK], pv[PIXEL_CHUNK], pz[PIXEL_CHUNK], pzh[PIXEL_CHUNK];
  float pgx[PIXEL_CHUNK], pgy[PIXEL_CHUNK];
  int filtered[PIXEL_CHUNK];
  for (uint l = lanes; l < PIXEL_CHUNK; ++l) {
    vis[l] = pz[l] = pzh[l] = pgx[l] = pgy[l] = 0.0f;
    pu[l] = pv[l] = -1.0f;
    filtered[l] = 0;
  }
#ifdef VIEW_DEPTH
  // The strip's receivers' view depths, as view_depth_partials (depth_range.cl) reduces them, taken
  // in the set-up below (a single map: it runs once): a quality probe's hard test reads the
  // G-buffer the range needs anyway. Lanes past a small image's end count nothing; the last
  // strip overlaps its neighbour, which min and max ignore.
  float depth_lo[PIXEL_CHUNK], depth_hi[PIXEL_CHUNK];
  for (uint l = 0; l < PIXEL_CHUNK; ++l) depth_lo[l] = INFINITY, depth_hi[l] = -INFINITY;
  float eye_x = eye.x, eye_y = eye.y, eye_z = eye.z;
  float fwd_x = forward.x, fwd_y = forward.y, fwd_z = forward.z;
#endif
  for (uint f = 0; faces_present >> f; ++f) {
    if (!((faces_present >> f) & 1u)) continue;
#ifdef VIRTUAL
    float16 to_ndc = level_ndc[f];
    global const uint* table =
        page_table + (size_t)f * (map_size / PAGE_TEXELS) * (map_size / PAGE_TEXELS);
    // The level's texels across: map_size for a clipmap's level, fewer for a perspective mip.
    uint level_size = level_texels[f];
#elif defined(CUBE_FACES)
    float16 to_ndc = cube.to_ndc[f];
    uint level_size = map_size;
#else
    float16 to_ndc = lookup.to_ndc;
    uint level_size = map_size;
#endif
    int size = (int)level_size;
#ifdef VIRTUAL
    global const float* map = map0;  // the pool: every level's pages
#else
    global const float* map = f == 0   ? map0
                              : f == 1 ? map1
                              : f == 2 ? map2
                              : f == 3 ? map3
                              : f == 4 ? map4
                                       : map5;
#endif
    // The matrix as scalars (GLM column-major: m[4 * column + row]).
    float m[16];
    vstore16(to_ndc, 0, m);
#pragma clang loop vectorize_width(16)
    for (uint l = 0; l < lanes; ++l) {
      uint p = first + l;
      float x = px[l], y = py[l], zw = pw[l];
      float nx = nrm[4 * p], ny = nrm[4 * p + 1], nz = nrm[4 * p + 2], nw = nrm[4 * p + 3];
#ifdef VIEW_DEPTH
      float d = view_depth(x, y, zw, eye_x, eye_y, eye_z, fwd_x, fwd_y, fwd_z);
      int receives = receives_shadows(x, y, zw, nw);
      depth_lo[l] = receives ? d : INFINITY;
      depth_hi[l] = receives ? d : -INFINITY;
#endif
      float cx = row4(m[0], m[4], m[8], m[12], x, y, zw);
      float cy = row4(m[1], m[5], m[9], m[13], x, y, zw);
      float cz = row4(m[2], m[6], m[10], m[14], x, y, zw);
      float cw = row4(m[3], m[7], m[11], m[15], x, y, zw);
      float sx = cx / cw, sy = cy / cw, sz = cz / cw;
      float u = sx * level_size, w = sy * level_size;
      // The receiver plane's depth gradient per texel: depth_gradient() of the prelude,
      // unrolled. Tangent t1 = normalize(n x e), e = x axis unless n is close to it; t2 = n x t1.
      int ex = fabs(nx) < 0.9f;
      float ax = ex ? 0.0f : -nz, ay = ex ? nz : 0.0f, az = ex ? -ny : nx;
      float inv = 1.0f / sqrt(ax * ax + ay * ay + az * az);
      ax *= inv, ay *= inv, az *= inv;
      float bx = ny * az - nz * ay, by = nz * ax - nx * az, bz = nx * ay - ny * ax;
      float m1x = row3(m[0], m[4], m[8], ax, ay, az), m1y = row3(m[1], m[5], m[9], ax, ay, az);
      float m1z = row3(m[2], m[6], m[10], ax, ay, az), m1w = row3(m[3], m[7], m[11], ax, ay, az);
      float m2x = row3(m[0], m[4], m[8], bx, by, bz), m2y = row3(m[1], m[5], m[9], bx, by, bz);
      float m2z = row3(m[2], m[6], m[10], bx, by, bz), m2w = row3(m[3], m[7], m[11], bx, by, bz);
      // Reciprocals instead of divisions (the set-up's cost is mostly its divisions); the
      // gradient only sets the bias and the receiver plane, so an ulp does not matter.
      float rw = 1.0f / cw;
      float d1x = (m1x - sx * m1w) * rw, d1y = (m1y - sy * m1w) * rw;
      float d1z = (m1z - sz * m1w) * rw;
      float d2x = (m2x - sx * m2w) * rw, d2y = (m2y - sy * m2w) * rw;
      float d2z = (m2z - sz * m2w) * rw;
      float det = d1x * d2y - d2x * d1y, rdet = 1.0f / (det * level_size);
      float gx = (d1z * d2y - d2z * d1y) * rdet;
      float gy = (d1x * d2z - d2x * d1z) * rdet;
      int finite = (det != 0.0f) & isfinite(gx) & isfinite(gy);
      gx = finite ? fmin(fmax(gx, -MAX_SLOPE), MAX_SLOPE) : 0.0f;
      gy = finite ? fmin(fmax(gy, -MAX_SLOPE), MAX_SLOPE) : 0.0f;
      // An edge-on receiver (no finite gradient) gets the full MAX_SLOPE in the hard test, as
      // depth_slope() gives; the filters' receiver plane has no gradient there.
      float slope = finite ? fmin(fabs(gx) + fabs(gy), MAX_SLOPE) : 0.0f;
      float hard_slope = finite ? slope : MAX_SLOPE;
      float z = sz - (bias_constant + bias_slope * (mode == PCF_NEAREST ? hard_slope : slope));
      float z_hard = sz - (bias_constant + bias_slope * hard_slope);  // PCF_EDGE's hard test
      float lx = x - light_position.x, ly = y - light_position.y, lz = zw - light_position.z;
      float cone = (lx * light_axis.x + ly * light_axis.y + lz * light_axis.z) /
                   sqrt(lx * lx + ly * ly + lz * lz);
      int outside_cone = (light_kind == LIGHT_SPOT) & (cone < cos_half_cone);
      // A receiver whose seen side faces away from the light is in its own (attached) shadow,
      // whatever the map says, edge-on included (the soft filters' disk_above_horizon in the
      // prelude grades it over an area light's disk): near the terminator the slope bias grows
      // without bound and would light it. The normal faces the camera.
      float away = nx * (travel_x + along * lx) + ny * (travel_y + along * ly) +
                   nz * (travel_z + along * lz);
      int unlit = outside_cone | ((nw != 0.0f) & (away >= 0.0f));
      int off_map = (cw <= 0.0f) | (u < 0.0f) | (w < 0.0f) | (u >= level_size) | (w >= level_size);
#ifdef VIRTUAL
      off_map |= pixel_level[p] == NO_LEVEL;
#endif
      // 1: not a receiver, or off the map; PCF_EDGE: both tests agree there.
      vis[l] = isnan(x) ? NAN : mode == PCF_EDGE ? 0.0f : unlit ? 0.0f : 1.0f;
      filtered[l] = IN_FACE(l, f) & !isnan(x) & !unlit & (nw != 0.0f) & !off_map;
      // Unfiltered lanes get u = v = -1: their taps fall off the map and load nothing outside.
      pu[l] = filtered[l] ? u : -1.0f;
      pv[l] = filtered[l] ? w : -1.0f;
      pz[l] = z;
      pzh[l] = z_hard;
      pgx[l] = gx;
      pgy[l] = gy;
    }
    // A strip with nothing to filter (the sky, non-receivers) skips the taps.
    int any = 0;
    for (uint l = 0; l < PIXEL_CHUNK; ++l) any |= filtered[l];
    if (!any) {
    } else if (mode == PCF_NEAREST) {
      for (uint l = 0; l < PIXEL_CHUNK; ++l) {
        float v = TEXEL_TEST(floor_int(pu[l]), floor_int(pv[l]), pz[l]);
        vis[l] = filtered[l] ? v : vis[l];
      }
    } else if (mode == PCF_BILINEAR || mode == PCF_EDGE) {
      for (uint l = 0; l < PIXEL_CHUNK; ++l) {
        float tx = pu[l] - 0.5f, ty = pv[l] - 0.5f, gx = pgx[l], gy = pgy[l], z = pz[l];
        int i = floor_int(tx), j = floor_int(ty);
        float fx = tx - i, fy = ty - j;
        // Receiver-plane depth at each texel centre, relative to the point.
        float dz0 = -gx * fx - gy * fy;
        float v00 = TEXEL_TEST(i, j, z + dz0);
        float v10 = TEXEL_TEST(i + 1, j, z + dz0 + gx);
        float v01 = TEXEL_TEST(i, j + 1, z + dz0 + gy);
        float v11 = TEXEL_TEST(i + 1, j + 1, z + dz0 + gx + gy);
        float v = lerp(lerp(v00, v10, fx), lerp(v01, v11, fx), fy);
        vis[l] = filtered[l] ? v : vis[l];
      }
      if (mode == PCF_EDGE)
        for (uint l = 0; l < PIXEL_CHUNK; ++l) {
          float h = TEXEL_TEST(floor_int(pu[l]), floor_int(pv[l]), pzh[l]);
          vis[l] = filtered[l] ? fabs(h - vis[l]) : vis[l];
        }
    } else if (mode == PCF_POISSON) {
      float sum[PIXEL_CHUNK];
      for (uint l = 0; l < PIXEL_CHUNK; ++l) sum[l] = 0.0f;
      global const float* tap = (global const float*)taps;
      // Two taps per pass over the strip: the pixel set-up is loaded once for both.
      uint k = 0;
      for (; k + 1 < tap_count; k += 2) {
        float tx = tap[2 * k], ty = tap[2 * k + 1], ux = tap[2 * k + 2], uy = tap[2 * k + 3];
#pragma clang loop vectorize_width(16)
        for (uint l = 0; l < PIXEL_CHUNK; ++l) {
          float cs = pcs[l], sn = psn[l], u = pu[l], v = pv[l], z = pz[l];
          float gx = pgx[l], gy = pgy[l];
          // The rotated taps and the receiver plane at them in fma steps (one instruction each).
          float dx = fma(cs, tx, -sn * ty), dy = fma(sn, tx, cs * ty);
          float ex = fma(cs, ux, -sn * uy), ey = fma(sn, ux, cs * uy);
          sum[l] += TEXEL_TEST(floor_int(u + dx), floor_int(v + dy), fma(gy, dy, fma(gx, dx, z))) +
                    TEXEL_TEST(floor_int(u + ex), floor_int(v + ey), fma(gy, ey, fma(gx, ex, z)));
        }
      }
      if (k < tap_count) {
        float tx = tap[2 * k], ty = tap[2 * k + 1];
#pragma clang loop vectorize_width(16)
        for (uint l = 0; l < PIXEL_CHUNK; ++l) {
          float cs = pcs[l], sn = psn[l];
          float dx = fma(cs, tx, -sn * ty), dy = fma(sn, tx, cs * ty);
          sum[l] += TEXEL_TEST(floor_int(pu[l] + dx), floor_int(pv[l] + dy),
                               fma(pgy[l], dy, fma(pgx[l], dx, pz[l])));
        }
      }
      float scale = 1.0f / tap_count;  // exact for the power-of-two counts, an ulp otherwise
      for (uint l = 0; l < PIXEL_CHUNK; ++l) vis[l] = filtered[l] ? sum[l] * scale : vis[l];
    }
#ifdef PER_FACE
    for (uint l = 0; l < PIXEL_CHUNK; ++l) out[l] = face[l] == f ? vis[l] : out[l];
#endif
  }
#ifdef PER_FACE
#define RESULT(l) out[l]
#else
#define RESULT(l) vis[l]
#endif
  // Only [own, pixel_count) is written.
  for (uint l = own - first; l < PIXEL_CHUNK && first + l < pixel_count; ++l)
    visibility[first + l] = RESULT(l);
#ifdef VIEW_DEPTH
  depth_partials[get_global_id(0)] = min_max_halving(depth_lo, depth_hi, PIXEL_CHUNK);
#endif
#undef IN_FACE
#undef RESULT
#undef PER_FACE
}
