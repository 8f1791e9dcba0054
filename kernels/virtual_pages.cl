// Virtual shadow maps (issue 53): which pages of a directional light's clipmap the camera's
// pixels read (engine/light/virtual_levels.hpp has the levels and their windows). Per pixel:
// - its footprint in light space: the larger light-space offset to its right and lower
//   neighbours, or its own world size where a neighbour lies across a depth jump (or is sky);
// - the coarsest level whose texel is at most footprint * 2^bias (`scale`), found exactly from the
//   float's exponent (no log2, whose rounding is each device's own), or a coarser one until the
//   level's window holds the pixel with its margin;
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
// device (log2, frexp and ldexp are library calls that PoCL does not inline: the marking took 4x
// as long with them). x below FLT_MIN counts as FLT_MIN.
inline int floor_log2(float x) {
  return (int)((as_uint(fmax(x, FLT_MIN)) >> 23) & 0xffu) - 127;
}
inline float pow2(int n) {
  return as_float((uint)(n + 127) << 23);
}

kernel void virtual_mark(global const float* position, uint width, uint pixel_count, float4 eye,
                         float pixel_angle, float4 light_u, float4 light_v, int first_level,
                         uint level_count, global const float2* first_page, uint texels,
                         float scale, float reach, float coarsen_beyond, global uchar* marks,
                         global uint* counts, global uchar* pixel_level) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  if (first >= pixel_count) return;  // the GPU shape's last work-group runs past the end
  uint last = min(first + PIXEL_CHUNK, pixel_count);
  uint pages = texels / PAGE_TEXELS, lost = 0, coarsened = 0;
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
    pixel_level[p] = NO_LEVEL;
    if (isnan(x.x)) continue;
    float distance = length3(x - eye.xyz), own = distance * pixel_angle, footprint = 0.0f;
    for (uint k = 0; k < 2; ++k) {
      uint q = k == 0 ? p + 1 : p + width;
      if ((k == 0 && (p % width) + 1 == width) || q >= pixel_count) continue;
      float3 y = vload3(q, position);
      float3 d = y - x;
      if (isnan(y.x) || length3(d) > 4.0f * own) continue;  // across a depth jump
      footprint = fmax(footprint, fmax(fabs(dot3(d, light_u.xyz)), fabs(dot3(d, light_v.xyz))));
    }
    if (footprint == 0.0f) footprint = own;
    int level = max(floor_log2(footprint * (float)texels * scale), first_level);
    // Coarsened at most to the coarsest level: never off the clipmap.
    int coarser = distance > coarsen_beyond ? floor_log2(distance / coarsen_beyond) + 1 : 0;
    coarser = min(coarser, max(first_level + (int)level_count - 1 - level, 0));
    level += coarser;
    float2 ls = (float2)(dot3(x, light_u.xyz) + light_u.w, dot3(x, light_v.xyz) + light_v.w);
    float2 t = (float2)(0.0f);
    for (; level < first_level + (int)level_count; ++level) {
      // ls over the level's texel 2^level / texels: exact scalings by powers of two.
      t = ls * (pow2(-level) * (float)texels) -
          first_page[level - first_level] * (float)PAGE_TEXELS;
      if (t.x >= reach && t.y >= reach && t.x < (float)texels - reach &&
          t.y < (float)texels - reach)
        break;
    }
    if (level >= first_level + (int)level_count) {  // past the coarsest level, or none holds it
      ++lost;
      continue;
    }
    coarsened += coarser > 0;
    pixel_level[p] = (uchar)(level - first_level);
    global uchar* table = marks + (size_t)(level - first_level) * pages * pages;
    for (int dy = -1; dy <= 1; dy += 2)
      for (int dx = -1; dx <= 1; dx += 2) {
        // t +- reach lies in [0, texels); min() for a sum that rounds up to texels.
        uint px = min((uint)((t.x + dx * reach) * (1.0f / PAGE_TEXELS)), pages - 1);
        uint py = min((uint)((t.y + dy * reach) * (1.0f / PAGE_TEXELS)), pages - 1);
        table[py * pages + px] = 1;
      }
  }
  counts[2 * get_global_id(0)] = lost;
  counts[2 * get_global_id(0) + 1] = coarsened;
}

// One work-item, in page order (so both kernel shapes give the same table): each marked page
// takes the pool's next slot while there is one; every other page, and a marked page past the
// pool's end, NO_PAGE. slot_page[slot]: the page (its index within its level) in each slot given.
// counter[0]: the slots given so far, counter[1]: the pages marked so far, over the request's
// lights (the pool is shared); counter[2 + l]: this light's level l's slots, which follow one
// another (the host skips levels without any and draws the others' tiles by slot), and
// counter[2 + MAX_LEVELS + 4 l ..]: their pages' bounding box (x0, y0, x1, y1), which binning
// keeps to.
kernel void virtual_allocate(global const uchar* marks, uint levels, uint across, uint pool_pages,
                             global uint* counter, global uint* table, global uint* slot_page) {
  if (get_global_id(0) != 0) return;
  uint level_pages = across * across;
  uint next = counter[0], marked = counter[1];
  for (uint l = 0; l < levels; ++l) {
    uint first = next, x0 = across, y0 = across, x1 = 0, y1 = 0;
    for (uint i = 0; i < level_pages; ++i) {
      uint slot = NO_PAGE;
      if (marks[l * level_pages + i]) {
        ++marked;
        if (next < pool_pages) {
          slot = next++;
          slot_page[slot] = i;
          uint x = i % across, y = i / across;
          x0 = min(x0, x), y0 = min(y0, y), x1 = max(x1, x), y1 = max(y1, y);
        }
      }
      table[l * level_pages + i] = slot;
    }
    counter[2 + l] = next - first;
    global uint* box = counter + 2 + MAX_LEVELS + 4 * l;
    box[0] = x0, box[1] = y0, box[2] = x1, box[3] = y1;
  }
  counter[0] = next;
  counter[1] = marked;
}
