// Virtual shadow maps (issue 53): which pages of a light's levels (a directional light's clipmap,
// a spot or point light's mip chains: engine/light/virtual_levels.hpp) the camera's pixels read.
// Per pixel:
// - its footprint in light space: the larger light-space offset to its right and lower
//   neighbours, or its own world size where a neighbour lies across a depth jump (or is sky);
// - the coarsest level whose texel is at most footprint * 2^bias (`scale`), found exactly from the
//   float's exponent (no log2, whose rounding is each device's own), or a coarser one until the
//   level's window holds the pixel with its margin (a clipmap's; a mip holds its whole face);
// - every page that `reach` texels around it meet, marked 1 in its level's table (a byte per
//   page, pages x pages a level). Work-items that mark one page write the same value.
// Where the pool cannot hold the pages, the pixels farther from the eye than `coarsen_beyond`
// read coarser levels: one more for each doubling of the distance past it, up to the coarsest
// (UE5 lowers distant pages' resolution in the same way). Per work-item, `counts` gets the pixels
// that no level holds and the pixels coarsened. Each pixel's level (its index from first_level;
// NO_LEVEL for the sky and pixels no level holds) goes to `pixel_level`, which the filters read
// (pcf.cl's VIRTUAL). virtual_allocate then gives the marked pages slots of the request's pool.

#ifndef PIXEL_CHUNK
#define PIXEL_CHUNK 64
#endif
#define PAGE_TEXELS 128
#define NO_LEVEL 0xff
#define NO_PAGE 0xffffffffu
#define MAX_LEVELS 32  // kMaxLevels

// floor(log2(x)) of a positive float, and 2^n, from the exponent bits: exact, and the same on every
// device (frexp and ldexp are library calls that PoCL does not inline: the marking took about
// 1.7x as long with them, against the camera view's raster). x below FLT_MIN counts as FLT_MIN.
inline int floor_log2(float x) {
  return (int)((as_uint(fmax(x, FLT_MIN)) >> 23) & 0xffu) - 127;
}
inline float pow2(int n) {
  return as_float((uint)(n + 127) << 23);
}

// A perspective map's texture point of x (mip 0's NDC across, as pcf.cl computes it), or none
// (NAN) behind the light or where the face decides nothing (an all-zero matrix).
inline float2 face_point(float16 m, float3 x) {
  float cw = row4(m.s3, m.s7, m.sb, m.sf, x.x, x.y, x.z);
  if (!(cw > 0.0f)) return (float2)(NAN);
  return (float2)(row4(m.s0, m.s4, m.s8, m.sc, x.x, x.y, x.z) / cw,
                  row4(m.s1, m.s5, m.s9, m.sd, x.x, x.y, x.z) / cw);
}

// Light space, per light kind (faces: 0 a directional clipmap, whose light space is the rows u
// and v of to_light[0] in world units; 1 a spot light's map; 6 a point light's cube faces, which
// `cube` picks between). A perspective map's light space is its face's mip 0 texture NDC, so that
// its mip m's texel, 2^m / texels, is a directional level's 2^level / texels: the level
// arithmetic below is one for both, with first_level = 0 and first pages 0.
kernel void virtual_mark(global const float* position, uint width, uint pixel_count, float4 eye,
                         float pixel_angle, global const float16* to_light, uint faces,
                         faces_t cube, int first_level, uint level_count,
                         global const float2* first_page, uint texels, float scale, float reach,
                         float4 soft, float coarsen_beyond, global uchar* marks,
                         global uint* counts, global uchar* pixel_level) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  if (first >= pixel_count) return;  // the GPU shape's last work-group runs past the end
  uint last = min(first + PIXEL_CHUNK, pixel_count);
  uint pages = texels / PAGE_TEXELS, lost = 0, coarsened = 0;
  float16 m0 = to_light[0];
  float4 light_u = (float4)(m0.s0, m0.s4, m0.s8, m0.sc),
         light_v = (float4)(m0.s1, m0.s5, m0.s9, m0.sd);
  // Levels per face: a perspective map's mips, or the whole clipmap.
  int mips = faces > 0 ? (int)level_count / (int)faces : (int)level_count;
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    pixel_level[p] = NO_LEVEL;
    if (isnan(x.x)) continue;
    uint face = faces == 6 ? cube_face(&cube, x.x, x.y, x.z) : 0;
    float16 m = to_light[face];
    float2 ls = faces > 0 ? face_point(m, x) : (float2)(0.0f);
    if (isnan(ls.x)) continue;  // off a perspective map: lit, as off a dense one
    float distance = length3(x - eye.xyz), own = distance * pixel_angle, footprint = 0.0f;
    for (uint k = 0; k < 2; ++k) {
      uint q = k == 0 ? p + 1 : p + width;
      if ((k == 0 && (p % width) + 1 == width) || q >= pixel_count) continue;
      float3 y = vload3(q, position);
      float3 d = y - x;
      if (isnan(y.x) || length3(d) > 4.0f * own) continue;  // across a depth jump
      if (faces > 0) {
        float2 e = face_point(m, y) - ls;
        if (!isnan(e.x)) footprint = fmax(footprint, fmax(fabs(e.x), fabs(e.y)));
      } else {
        footprint = fmax(footprint, fmax(fabs(dot3(d, light_u.xyz)), fabs(dot3(d, light_v.xyz))));
      }
    }
    if (footprint == 0.0f && faces > 0) {  // its own world size along each axis, projected
      for (uint a = 0; a < 3; ++a) {
        float3 y = x + (float3)(a == 0 ? own : 0.0f, a == 1 ? own : 0.0f, a == 2 ? own : 0.0f);
        float2 e = face_point(m, y) - ls;
        if (!isnan(e.x)) footprint = fmax(footprint, fmax(fabs(e.x), fabs(e.y)));
      }
    }
    if (footprint == 0.0f) footprint = own;
    int level = floor_log2(footprint * (float)texels * scale);
    if (soft.x > 0.0f) {
      // PCSS (pcss.cl): a level whose texels hold the blocker search within `reach`. The search
      // radius: a sun's (d - near) tan(theta / 2) world units, a spot light's size (d - near) /
      // (d near) units of x / d; times soft.z, level 0's texels per unit. d: linear depth.
      float d =
          faces > 0 ? row4(m.s3, m.s7, m.sb, m.sf, x.x, x.y, x.z) : -(dot3(x, m0.s26a.xyz) + m0.se);
      float search = faces > 0 ? soft.x * (d - soft.y) / (d * soft.y) : (d - soft.y) * soft.x;
      float texels0 = search * soft.z;
      if (texels0 > reach) level = max(level, floor_log2(texels0 / reach) + 1);
    }
    // A footprint past the coarsest level's texel reads the coarsest level (finer than it asks).
    int lowest = faces > 0 ? 0 : first_level, highest = lowest + mips - 1;
    level = clamp(level, lowest, highest);
    // Coarsened at most to the coarsest level: never off the clipmap.
    int coarser = distance > coarsen_beyond ? floor_log2(distance / coarsen_beyond) + 1 : 0;
    coarser = min(coarser, max(highest - level, 0));
    level += coarser;
    float2 t = (float2)(0.0f);
    int index = -1;  // the level's place in the tables
    uint extent = texels;
    if (faces > 0) {
      // A mip's texture is [0, texels >> level): taps past its edge read nothing, as a dense
      // map's, and the pages they meet are clamped to it.
      t = ls * (pow2(-level) * (float)texels);
      extent = texels >> level;
      if (t.x >= 0.0f && t.y >= 0.0f && t.x < (float)extent && t.y < (float)extent)
        index = (int)face * mips + level;
    } else {
      ls = (float2)(dot3(x, light_u.xyz) + light_u.w, dot3(x, light_v.xyz) + light_v.w);
      for (; level < first_level + (int)level_count; ++level) {
        // ls over the level's texel 2^level / texels: exact scalings by powers of two.
        t = ls * (pow2(-level) * (float)texels) -
            first_page[level - first_level] * (float)PAGE_TEXELS;
        if (t.x >= reach && t.y >= reach && t.x < (float)texels - reach &&
            t.y < (float)texels - reach) {
          index = level - first_level;
          break;
        }
      }
    }
    if (index < 0) {  // past the coarsest level, or none holds it; off a perspective map
      lost += faces == 0;
      continue;
    }
    coarsened += coarser > 0;
    pixel_level[p] = (uchar)index;
    global uchar* table = marks + (size_t)index * pages * pages;
    // The pages of the taps' square's corners (reach < a page: at most four), clamped to the
    // level's texture (rows of extent / PAGE_TEXELS pages); clamped too for a sum that rounds up
    // to the edge. Written whether marked or not: a test before each write made the pass 1.7x
    // slower on PoCL.
    int across = (int)(extent / PAGE_TEXELS), edge = across - 1;
    int x0 = clamp((int)floor((t.x - reach) * (1.0f / PAGE_TEXELS)), 0, edge);
    int x1 = clamp((int)floor((t.x + reach) * (1.0f / PAGE_TEXELS)), 0, edge);
    int y0 = clamp((int)floor((t.y - reach) * (1.0f / PAGE_TEXELS)), 0, edge);
    int y1 = clamp((int)floor((t.y + reach) * (1.0f / PAGE_TEXELS)), 0, edge);
    table[y0 * across + x0] = 1;
    table[y0 * across + x1] = 1;
    table[y1 * across + x0] = 1;
    table[y1 * across + x1] = 1;
  }
  counts[2 * get_global_id(0)] = lost;
  counts[2 * get_global_id(0) + 1] = coarsened;
}

// The pages a light's marks ask for: counted before any slot is given, so that the coarsening
// search (the host's) changes nothing of the pool. One work-item; counter[0] += the marks.
kernel void virtual_count(global const uchar* marks, uint page_count, global uint* counter) {
  if (get_global_id(0) != 0) return;
  uint n = 0;
  for (uint i = 0; i < page_count; ++i) n += marks[i];
  counter[0] = n;
}

// A page's key across frames: its light, its level (absolute), its place in the level's page
// grid (absolute) and its window's first page: the raster's rounding depends on the window, so a
// page keeps its texels (the same bits as drawing it again) while its window stays. A slot
// nobody owns has NO_PAGE for its light (page coordinates take every int).
typedef struct {
  uint light;
  int level, x, y, window_x, window_y, pad0, pad1;
} page_key_t;

inline bool same_key(page_key_t a, page_key_t b) {
  return a.light == b.light && a.level == b.level && a.x == b.x && a.y == b.y &&
         a.window_x == b.window_x && a.window_y == b.window_y;
}
inline uint key_hash(page_key_t k, uint mask) {
  uint h = k.light * 0x9e3779b1u ^ (uint)k.level * 0x85ebca77u ^ (uint)k.x * 0xc2b2ae3du ^
           (uint)k.y * 0x27d4eb2fu ^ (uint)k.window_x * 0x165667b1u ^ (uint)k.window_y;
  return (h ^ (h >> 15)) & mask;
}
inline page_key_t page_key(uint light, int first_level, global const float2* first_page,
                           uint across, uint l, uint i) {
  int2 w = convert_int2(first_page[l]);
  page_key_t k = {
      light, first_level + (int)l, w.x + (int)(i % across), w.y + (int)(i / across), w.x, w.y, 0,
      0};
  return k;
}

// Slots for one light's marked pages, kept across a sequence's frames (issue 53). One work-item,
// in page order, so both kernel shapes give the same tables:
// 1. the slots owned by a page are found through `hash` (open addressing, rebuilt here from the
//    owners); a marked page that owns one keeps it (its texels stay while slot_valid);
// 2. the other marked pages take the slots no page of this frame holds, the least recently
//    marked first (never owned before any owned; then by age in frames, up to 8), NO_PAGE once
//    none is left;
// 3. a page whose slot is not valid is drawn: (slot, page) goes to draw_list (the levels in order)
//    and its slot to draw_table (NO_PAGE elsewhere: what binning draws), and it becomes valid.
// table: each page's slot. counter[0] the slots this frame holds, [1] the pages marked, [2] the
// pages drawn, over the request's lights; [3 + l] level l's drawn pages (consecutive in
// draw_list), [3 + MAX_LEVELS + 4 l ..] their bounding box (x0, y0, x1, y1).
kernel void virtual_allocate(global const uchar* marks, uint levels, uint across, uint mips,
                             int first_level, global const float2* first_page, uint light,
                             uint frame, uint pool_pages, uint hash_mask, global uint* counter,
                             global uint* table, global uint* draw_table,
                             global page_key_t* slot_owner, global uint* slot_frame,
                             global uint* slot_valid, global uint* hash, global uint2* draw_list) {
  if (get_global_id(0) != 0) return;
  uint level_pages = across * across, page_count = levels * level_pages;
  // A level's pages in rows of its own width: a perspective map's mip m has across >> m.
#define ACROSS(l) (mips > 0 ? across >> ((l) % mips) : across)
  for (uint h = 0; h <= hash_mask; ++h) hash[h] = NO_PAGE;
  for (uint s = 0; s < pool_pages; ++s) {
    if (slot_owner[s].light == NO_PAGE) continue;
    uint h = key_hash(slot_owner[s], hash_mask);
    while (hash[h] != NO_PAGE) h = (h + 1) & hash_mask;
    hash[h] = s;
  }
  uint held = counter[0], marked = counter[1], drawn = counter[2];
  // 1. Pages that own a slot keep it.
  for (uint l = 0; l < levels; ++l)
    for (uint i = 0; i < level_pages; ++i) {
      uint at = l * level_pages + i, slot = NO_PAGE;
      if (marks[at]) {
        ++marked;
        page_key_t k = page_key(light, first_level, first_page, ACROSS(l), l, i);
        for (uint h = key_hash(k, hash_mask); hash[h] != NO_PAGE; h = (h + 1) & hash_mask)
          if (same_key(slot_owner[hash[h]], k)) {
            slot = hash[h];
            slot_frame[slot] = frame;
            ++held;
            break;
          }
        if (slot == NO_PAGE) slot = NO_PAGE - 1;  // wants one
      }
      table[at] = slot;
    }
  // 2. The others take free slots, never owned first, then the least recently marked.
  uint at = 0;
  for (uint age = 0; age <= 9 && at < page_count; ++age)  // 0: never owned; 1..8: 9 - age frames
    for (uint s = 0; s < pool_pages && at < page_count; ++s) {
      bool owned = slot_owner[s].light != NO_PAGE;
      uint since = frame - slot_frame[s];             // frames since it was last marked
      if (slot_frame[s] == frame && owned) continue;  // this frame's
      if (age == 0 ? owned : !owned || min(since, 9u) != 10 - age) continue;
      while (at < page_count && table[at] != NO_PAGE - 1) ++at;
      if (at == page_count) break;
      uint l = at / level_pages, i = at % level_pages;
      slot_owner[s] = page_key(light, first_level, first_page, ACROSS(l), l, i);
      slot_frame[s] = frame;
      slot_valid[s] = 0;
      table[at++] = s;
      ++held;
    }
  // 3. Draw the pages whose slots hold no valid texels.
  uint listed = drawn;
  for (uint l = 0; l < levels; ++l) {
    uint x0 = across, y0 = across, x1 = 0, y1 = 0, level_drawn = 0, row = ACROSS(l);
    for (uint i = 0; i < level_pages; ++i) {
      uint a = l * level_pages + i, slot = table[a];
      if (slot == NO_PAGE - 1) slot = table[a] = NO_PAGE;  // past the pool
      uint draw = NO_PAGE;
      if (slot != NO_PAGE && !slot_valid[slot]) {
        draw = slot;
        slot_valid[slot] = 1;
        draw_list[listed++] = (uint2)(slot, i);
        ++level_drawn;
        uint x = i % row, y = i / row;
        x0 = min(x0, x), y0 = min(y0, y), x1 = max(x1, x), y1 = max(y1, y);
      }
      draw_table[a] = draw;
    }
    counter[3 + l] = level_drawn;
    global uint* box = counter + 3 + MAX_LEVELS + 4 * l;
    box[0] = x0, box[1] = y0, box[2] = x1, box[3] = y1;
  }
  counter[0] = held;
  counter[1] = marked;
  counter[2] = listed;
#undef ACROSS
}

// Slots whose texels a change makes stale (issue 53): every slot of `light` (all != 0), or those
// whose page's light-space square meets one of `boxes` (x0, y0, x1, y1 in light-space units,
// grown by a texel of their level for the raster's snapping). A work-item per slot.
kernel void virtual_invalidate(global const page_key_t* slot_owner, uint pool_pages, uint light,
                               uint all, global const float4* boxes, uint box_count, uint texels,
                               global uint* slot_valid) {
  uint s = get_global_id(0);
  if (s >= pool_pages) return;
  page_key_t k = slot_owner[s];
  if (k.light != light) return;
  float texel = pow2(k.level) / (float)texels, page = texel * PAGE_TEXELS;
  float x0 = k.x * page - texel, y0 = k.y * page - texel;
  float x1 = x0 + page + 2 * texel, y1 = y0 + page + 2 * texel;
  bool stale = all != 0;
  for (uint b = 0; b < box_count && !stale; ++b) {
    float4 r = boxes[b];
    stale = r.x <= x1 && r.z >= x0 && r.y <= y1 && r.w >= y0;
  }
  if (stale) slot_valid[s] = 0;
}

// PRODUCT_VIRTUAL_PAGES's images (issue 53), a work-item per PIXEL_CHUNK values:
// - the pool with the slots this frame's pages hold (slot_frame == frame), 1.0 (empty) in the
//   others, whose texels are an earlier request's;
// - a light's page tables as floats, -1 where a page has no slot (slot numbers are exact in
//   float up to 2^24);
// - each camera pixel's level index as a float, NaN where it has none.
kernel void virtual_pool_image(global const float* pool, global const uint* slot_frame, uint frame,
                               uint texel_count, global float* out) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  for (uint i = first; i < min(first + PIXEL_CHUNK, texel_count); ++i)
    out[i] = slot_frame[i / (PAGE_TEXELS * PAGE_TEXELS)] == frame ? pool[i] : 1.0f;
}

kernel void virtual_table_image(global const uint* table, uint count, global float* out) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  for (uint i = first; i < min(first + PIXEL_CHUNK, count); ++i)
    out[i] = table[i] == NO_PAGE ? -1.0f : (float)table[i];
}

kernel void virtual_level_image(global const uchar* pixel_level, uint count, global float* out) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  for (uint i = first; i < min(first + PIXEL_CHUNK, count); ++i)
    out[i] = pixel_level[i] == NO_LEVEL ? NAN : (float)pixel_level[i];
}
