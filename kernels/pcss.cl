// Percentage-closer soft shadows (Fernando 2005; seed 001): per camera pixel,
//   1. blocker search: the average LINEAR light depth d_b of map texels nearer than the receiver
//      within the region through which the receiver sees the light (radius from the light's size,
//      the map's near plane and the receiver's depth d_r),
//   2. penumbra: w = (d_r - d_b) * W_light / d_b (directional: W_light / d_b -> the angular
//      diameter, w = (d_r - d_b) * 2 tan(theta / 2)),
//   3. Poisson PCF with radius w / 2 projected into texels.
// Linear depth d from the map's NDC z: spot z = alpha + beta / d, directional z = alpha + beta d.
// Each tap compares against the receiver plane's depth at the tap, as in pcf.cl.

// pcss's GPU shape (engine/passes/pixel_shape.hpp) builds this file with -DPIXEL_CHUNK=1 and
// launches it in work-groups: a work-item per pixel, each pixel's arithmetic as here.
#ifndef PIXEL_CHUNK
#define PIXEL_CHUNK 64
#endif
#define MAX_TAPS 64

inline float lin_depth(float z, int perspective, float alpha, float beta) {
  return perspective ? beta / (z - alpha) : (z - alpha) / beta;
}

// 1 lit, 0 shadowed; texels off the map are lit (the map covers every caster).
inline float map_depth(global const float* map, int size, float u, float v) {
  int i = (int)floor(u), j = (int)floor(v);
  if (i < 0 || j < 0 || i >= size || j >= size) return 1.0f;
  return map[(size_t)j * size + i];
}

// Virtual maps (issue 53), built with -DVIRTUAL: each pixel reads its level (pixel_level, from
// marking: the level whose texels hold its blocker search within max_search texels) through the
// level's page table into the pool (`map`), as pcf.cl's VIRTUAL does; a page without a slot
// holds no blocker, as off a dense map.
#define PAGE_TEXELS 128
#define NO_PAGE 0xffffffffu
#define NO_LEVEL 0xff
inline float page_depth(global const float* pool, global const uint* table, int size, float u,
                        float v) {
  int i = (int)floor(u), j = (int)floor(v);
  if (i < 0 || j < 0 || i >= size || j >= size) return 1.0f;
  uint slot = table[(j / PAGE_TEXELS) * (size / PAGE_TEXELS) + i / PAGE_TEXELS];
  if (slot == NO_PAGE) return 1.0f;
  return pool[(size_t)slot * (PAGE_TEXELS * PAGE_TEXELS) + (j % PAGE_TEXELS) * PAGE_TEXELS +
              i % PAGE_TEXELS];
}
#ifdef VIRTUAL
#define MAP_ARG global const float *map, global const uint *table
#define MAP_PASS map, table
#define MAP_DEPTH(size, u, v) page_depth(map, table, size, u, v)
#else
#define MAP_ARG global const float* map
#define MAP_PASS map
#define MAP_DEPTH(size, u, v) map_depth(map, size, u, v)
#endif

// Interleaved gradient noise (as pcf.cl): a per-pixel rotation angle.
inline float pcss_angle(uint p, uint width) {
  float x = (float)(p % width), y = (float)(p / width);
  float a = 0.06711056f * x + 0.00583715f * y;
  a = 52.9829189f * (a - floor(a));
  return 6.2831853f * (a - floor(a));
}

// Steps 1 and 2 for the receiving point x (normal n) inside the light: the penumbra's
// half-width at the receiver in light units (x / d or world), or 0 when x is off the map or no
// texel blocks it (lit). Also gives the receiver's map texel (u, v), its biased depth z and
// depth gradient g for the filter.
// `taps`: the blocker pattern, unit disk. `size`: spot radius, or tan(theta / 2) for a
// directional light. `scale`: texels per unit of x / d (spot) or per world unit (directional),
// along u and v (a fitted map need not be square in the world). `max_search`: cap of the search
// radius in texels. (cs, sn): the pattern's rotation.
inline float pcss_search(float3 x, float3 n, const shadow_lookup_t* lookup, MAP_ARG,
                         global const float2* taps, uint blocker_count, float cs, float sn,
                         int perspective, float alpha, float beta, float size, float2 scale,
                         float max_search, float* u_out, float* v_out, float* z_out, float2* g_out,
                         float* search_out) {
  uint map_size = lookup->map_size;
  int msize = (int)map_size;
  float4 c = mul_m4(lookup->to_ndc, (float4)(x, 1.0f));
  float3 s = c.xyz / c.w;
  float u = s.x * map_size, v = s.y * map_size;
  if (c.w <= 0.0f || u < 0.0f || v < 0.0f || u >= map_size || v >= map_size) return 0.0f;
  float2 g = depth_gradient(lookup->to_ndc, n, c, map_size);
  g = isfinite(g.x) && isfinite(g.y) ? clamp(g, -MAX_SLOPE, MAX_SLOPE) : (float2)(0.0f);
  float z =
      s.z - (lookup->bias_constant + lookup->bias_slope * fmin(fabs(g.x) + fabs(g.y), MAX_SLOPE));
  float d_r = lin_depth(s.z, perspective, alpha, beta);
  float near_d = lin_depth(0.0f, perspective, alpha, beta);
  *u_out = u, *v_out = v, *z_out = z, *g_out = g;
  // 1. Blocker search (projected onto the near plane for a spot light).
  // Radii in light units, then texels per axis.
  float search = perspective ? size * (d_r - near_d) / d_r / near_d : (d_r - near_d) * size;
  search = clamp(search, 0.5f / fmin(scale.x, scale.y), max_search / fmax(scale.x, scale.y));
  *search_out = search;
  float sum_d = 0.0f;
  uint blockers = 0;
  for (uint k = 0; k < blocker_count; ++k) {
    float2 t = taps[k];
    float2 d = search * scale * (float2)(cs * t.x - sn * t.y, sn * t.x + cs * t.y);
    float zm = MAP_DEPTH(msize, u + d.x, v + d.y);
    float zt = z + g.x * d.x + g.y * d.y;
    float dm = lin_depth(zm, perspective, alpha, beta);
    if (zm < 1.0f && dm < lin_depth(zt, perspective, alpha, beta)) {
      sum_d += dm;
      ++blockers;
    }
  }
  if (blockers == 0) return 0.0f;
  // 2. Penumbra half-width at the receiver.
  float d_b = sum_d / blockers;
  return perspective ? (d_r - d_b) * size / d_b / d_r : (d_r - d_b) * size;
}

// One camera pixel at world point x (normal n): its visibility, as pcss below writes it.
// `off_map`: a virtual map's pixel that no level holds (lit, as off a dense map).
inline float pcss_pixel(uint p, uint width, float3 x, float4 n, const shadow_lookup_t* lookup,
                        MAP_ARG, global const float2* taps, uint blocker_count, uint filter_count,
                        int rotate, int perspective, float alpha, float beta, float size,
                        float2 scale, float max_search, int off_map) {
  int msize = (int)lookup->map_size;
  float vis = 1.0f;
  float above = 1.0f;  // a receiver's share of the light's disk above its horizon
  float cs = 1.0f, sn = 0.0f;
  if (rotate) sn = sin_cos(pcss_angle(p, width), &cs);
  float u, v, z;
  float2 g;
  if (isnan(x.x)) {
    vis = NAN;
  } else if (outside_spot_cone(x, &lookup->light)) {
    vis = 0.0f;
  } else if (n.w != 0.0f && (above = disk_above_horizon(x, n.xyz, &lookup->light)) == 0.0f) {
    vis = 0.0f;
  } else if (n.w != 0.0f && !off_map) {
    float search;
    float half_w = pcss_search(x, n.xyz, lookup, MAP_PASS, taps, blocker_count, cs, sn, perspective,
                               alpha, beta, size, scale, max_search, &u, &v, &z, &g, &search);
    if (half_w > 0.0f) {
      // 3. Variable-radius PCF.
      float radius = fmax(half_w, 0.5f / fmin(scale.x, scale.y));
#ifdef VIRTUAL
      // Within the search's reach, whose pages marking gave slots (a penumbra wider than a
      // capped search would read past them).
      radius = fmin(radius, search);
#endif
      float lit = 0.0f;
      for (uint k = 0; k < filter_count; ++k) {
        float2 t = taps[MAX_TAPS + k];
        float2 d = radius * scale * (float2)(cs * t.x - sn * t.y, sn * t.x + cs * t.y);
        float zt = z + g.x * d.x + g.y * d.y;
        lit += zt <= MAP_DEPTH(msize, u + d.x, v + d.y) ? 1.0f : 0.0f;
      }
      vis = lit / filter_count;
    }
  }
  return isnan(vis) ? vis : fmin(vis, above);
}

// `taps`: blocker pattern in [0, MAX_TAPS), filter pattern in [MAX_TAPS, 2 MAX_TAPS).
kernel void pcss(global const float* position, global const float4* normal, uint pixel_count,
                 uint width, shadow_lookup_t lookup, global const float* map,
                 global const float2* taps, uint blocker_count, uint filter_count, int rotate,
                 int perspective, float alpha, float beta, float size, float2 scale,
                 float max_search, global float* visibility
#ifdef VIRTUAL
                 ,
                 global const uint* page_table, global const float16* level_ndc,
                 global const uint* level_texels, global const float4* level_geometry,
                 global const uchar* pixel_level
#endif
) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, pixel_count);
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    float4 n = normal[p];
#ifdef VIRTUAL
    // The pixel's level as a map of its own: matrix, texels across, depth mapping and scale, in
    // private copies (the kernel's arguments are shared by a work-group's work-items).
    uint level = pixel_level[p], li = level == NO_LEVEL ? 0 : level;
    uint pages = lookup.map_size / PAGE_TEXELS;  // a level's table block: pages^2 entries
    shadow_lookup_t own = lookup;
    own.to_ndc = level_ndc[li];
    own.map_size = level_texels[li];
    float4 geo = level_geometry[li];
    visibility[p] = pcss_pixel(p, width, x, n, &own, map, page_table + (size_t)li * pages * pages,
                               taps, blocker_count, filter_count, rotate, perspective, geo.x, geo.y,
                               size, geo.zw, max_search, level == NO_LEVEL);
#else
    visibility[p] = pcss_pixel(p, width, x, n, &lookup, map, taps, blocker_count, filter_count,
                               rotate, perspective, alpha, beta, size, scale, max_search, 0);
#endif
  }
}

#ifndef VIRTUAL
// The soft atlas' first step (atlas_soften.cl): the penumbra's half-width (light units; 0: lit
// or off the map) at every baked atlas texel, outside a spot's cone too (atlas_lookup applies the
// cone per pixel, and a pixel inside reads texels outside): the blocker search runs once per
// surface point and light, whatever the cameras. The pattern rotates per texel.
kernel void pcss_penumbra(global const float* position, global const float4* normal,
                          uint texel_count, uint width, shadow_lookup_t lookup,
                          global const float* map, global const float2* taps, uint blocker_count,
                          int rotate, int perspective, float alpha, float beta, float size,
                          float2 scale, float max_search, global float* half_width) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, texel_count);
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    float w = 0.0f;
    if (!isnan(x.x)) {
      float cs = 1.0f, sn = 0.0f;
      if (rotate) sn = sin_cos(pcss_angle(p, width), &cs);
      float u, v, z, search;
      float2 g;
      w = pcss_search(x, normal[p].xyz, &lookup, MAP_PASS, taps, blocker_count, cs, sn, perspective,
                      alpha, beta, size, scale, max_search, &u, &v, &z, &g, &search);
    }
    half_width[p] = w;
  }
}
#endif
