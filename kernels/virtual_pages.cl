// Virtual shadow maps (issue 53): which pages of a directional light's clipmap the camera's
// pixels read (engine/light/virtual_levels.hpp has the levels and their windows). Per pixel:
// - its footprint in light space: the larger light-space offset to its right and lower
//   neighbours, or its own world size where a neighbour lies across a depth jump (or is sky);
// - the coarsest level whose texel is at most footprint * 2^bias (`scale`), found exactly by
//   frexp (no log2, whose rounding is each device's own), or a coarser one until the level's
//   window holds the pixel with its margin;
// - every page that `reach` texels around it meet, marked 1 in its level's table (a byte per
//   page, pages x pages a level). Work-items that mark one page write the same value.
// Where the pool cannot hold the pages, the pixels farther from the eye than `coarsen_beyond`
// read coarser levels: one more for each doubling of the distance past it (UE5 lowers distant
// pages' resolution in the same way). Per work-item, `counts` gets the pixels that no level holds
// and the pixels coarsened. Each pixel's
// level (its index from first_level; NO_LEVEL for the sky and pixels no level holds) goes to
// `pixel_level`, which the filters read (pcf.cl's VIRTUAL).
// virtual_allocate then gives the marked pages slots of the request's pool.

#ifndef PIXEL_CHUNK
#define PIXEL_CHUNK 64
#endif
#define PAGE_TEXELS 128
#define NO_LEVEL 0xff
#define NO_PAGE 0xffffffffu

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
    // footprint * texels * scale = m 2^e, m in [0.5, 1): floor(log2) = e - 1.
    int e;
    frexp(footprint * (float)texels * scale, &e);
    int level = max(e - 1, first_level);
    int coarser = 0;
    if (distance > coarsen_beyond) {  // floor(log2(distance / coarsen_beyond)) + 1
      frexp(distance / coarsen_beyond, &coarser);
      level += coarser;
    }
    float2 ls = (float2)(dot3(x, light_u.xyz) + light_u.w, dot3(x, light_v.xyz) + light_v.w);
    float2 t = (float2)(0.0f);
    for (; level < first_level + (int)level_count; ++level) {
      float texel = ldexp(1.0f, level) / (float)texels;
      t = ls / texel - first_page[level - first_level] * (float)PAGE_TEXELS;
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
        uint px = min((uint)((t.x + dx * reach) / (float)PAGE_TEXELS), pages - 1);
        uint py = min((uint)((t.y + dy * reach) / (float)PAGE_TEXELS), pages - 1);
        table[py * pages + px] = 1;
      }
  }
  counts[2 * get_global_id(0)] = lost;
  counts[2 * get_global_id(0) + 1] = coarsened;
}

// One work-item, in page order (so both kernel shapes give the same table): each marked page
// takes the pool's next slot while there is one; every other page, and a marked page past the
// pool's end, NO_PAGE. counter[0]: the slots given so far, counter[1]: the pages marked so far,
// over the request's lights (the pool is shared); counter[2 + l]: this light's level l's slots
// (the host skips levels without any).
kernel void virtual_allocate(global const uchar* marks, uint levels, uint level_pages,
                             uint pool_pages, global uint* counter, global uint* table) {
  if (get_global_id(0) != 0) return;
  uint next = counter[0], marked = counter[1];
  for (uint l = 0; l < levels; ++l) {
    uint first = next;
    for (uint i = l * level_pages; i < (l + 1) * level_pages; ++i) {
      uint slot = NO_PAGE;
      if (marks[i]) {
        ++marked;
        if (next < pool_pages) slot = next++;
      }
      table[i] = slot;
    }
    counter[2 + l] = next - first;
  }
  counter[0] = next;
  counter[1] = marked;
}
