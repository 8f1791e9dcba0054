// Depth rasterization, GPU shape (issue 42), after Laine & Karras 2011 ("High-Performance
// Software Rasterization on GPUs"). Transform and set-up are raster.cl's own kernels built with a
// vertex and a triangle per work-item (-DVERTEX_CHUNK=1 -DTRIANGLE_CHUNK=1 -DVECTOR_SETUP=0), so
// the records are the same; binning and the raster are these:
//   bin_gpu_count    a work-item per record: atomic counts per tile, the boxes' pixels per group
//   bin_gpu_scan     one work-group: the tiles' first entries and the totals raster.cl's
//                    bin_scan_totals gives (entries, box pixels, records wanted), which the
//                    host reads
//   bin_gpu_scatter  a work-item per record: copies into its tiles' lists at atomic cursors
//   raster_gpu_tiles a work-group per TILE x TILE tile: the group stages the tile's records in
//                    local memory, GROUP at a time; each work-item owns a BLOCK_W x BLOCK_H block
//                    of the tile, its depths (and ids) in registers, and tests every record
//                    whose box meets the block
// The lists' order depends on the atomics, but the result does not: a texel keeps the least
// depth and, among equal depths, the lowest id (DEPTH_WRITE), and every pixel's coverage and
// depth are the same integer and float expressions as raster.cl's (raster_common.cl). So both
// shapes write the same bits. Hierarchical z (HIZ) is per block: once a record covered the whole
// block, records behind its deepest texel are skipped.

#include "raster_common.cl"

#ifndef GROUP
#define GROUP 256  // the work-group size: the device profile's, as -DGROUP
#endif
#ifndef HIZ
#define HIZ 1
#endif
// A tile's work-items: 16 across (a row of BLOCK_W-pixel blocks spans the tile, so a warp's
// writes are whole rows), GROUP / 16 down.
#define ITEMS_X 16
#define ITEMS_Y (GROUP / ITEMS_X)
#define BLOCK_W (TILE / ITEMS_X)
#define BLOCK_H (TILE / ITEMS_Y)
#if GROUP < ITEMS_X || TILE % ITEMS_X != 0 || TILE % ITEMS_Y != 0
#error "raster_gpu.cl needs GROUP a power of two from 16 to 16 * TILE"
#endif

// Work-item = record i: each tile its box meets counts it once; group_pixels[g] = the pixels of
// group g's boxes (the raster's load). Group indices come from the global id: a sliced launch's
// offset does not enter get_group_id.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void bin_gpu_count(
    global const tri_t* tris, uint triangle_total, uint capacity, global const uint* extra,
    uint tiles_x, volatile global uint* tile_count, global ulong* group_pixels) {
  local ulong pixels[GROUP];
  uint i = get_global_id(0), lid = get_local_id(0);
  uint tri_count = record_count(triangle_total, capacity, extra);
  ulong mine = 0;
  if (i < tri_count && !box_empty(tris + i)) {
    global const tri_t* r = tris + i;
    mine = box_pixels(r, 0);
    for (int ty = r->min_y / TILE; ty <= r->max_y / TILE; ++ty)
      for (int tx = r->min_x / TILE; tx <= r->max_x / TILE; ++tx)
        atomic_inc(tile_count + ty * tiles_x + tx);
  }
  pixels[lid] = mine;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) pixels[lid] += pixels[lid + span];
  }
  if (lid == 0) group_pixels[i / GROUP] = pixels[0];
}

// One work-group: tile_base[t] = the first list entry of tile t (an exclusive scan of the
// counts, each work-item a run of tiles); tile_base[tiles] = every entry, tile_base[tiles + 1] =
// every box pixel, tile_base[tiles + 2] = the records set-up wanted. 64-bit, so that the host can
// refuse (not wrap) bins that would not fit.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void bin_gpu_scan(
    global const uint* tile_count, uint tiles, global const ulong* group_pixels, uint groups,
    uint triangle_total, global const uint* extra, global ulong* tile_base) {
  local ulong sums[GROUP];
  uint lid = get_local_id(0);
  uint run = (tiles + GROUP - 1) / GROUP;
  uint t0 = min(lid * run, tiles), t1 = min(t0 + run, tiles);
  ulong own = 0;
  for (uint t = t0; t < t1; ++t) own += tile_count[t];
  sums[lid] = own;
  barrier(CLK_LOCAL_MEM_FENCE);
  // Hillis-Steele inclusive scan of the runs' sums.
  for (uint span = 1; span < GROUP; span *= 2) {
    ulong add = lid >= span ? sums[lid - span] : 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    sums[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  ulong at = sums[lid] - own;
  for (uint t = t0; t < t1; ++t) {
    tile_base[t] = at;
    at += tile_count[t];
  }
  if (lid == GROUP - 1) tile_base[tiles] = sums[lid];
  barrier(CLK_LOCAL_MEM_FENCE);
  ulong pixels = 0;
  for (uint g = lid; g < groups; g += GROUP) pixels += group_pixels[g];
  sums[lid] = pixels;
  for (uint span = GROUP / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < span) sums[lid] += sums[lid + span];
  }
  if (lid == 0) {
    tile_base[tiles + 1] = sums[0];
    tile_base[tiles + 2] = records_wanted(triangle_total, extra);
  }
}

// Work-item = record i, copied into each of its tiles' lists; `cursor` starts at zero.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void bin_gpu_scatter(
    global const tri_t* tris, uint triangle_total, uint capacity, global const uint* extra,
    uint tiles_x, volatile global uint* cursor, global const ulong* tile_base, global tri_t* bins) {
  uint i = get_global_id(0);
  if (i >= record_count(triangle_total, capacity, extra) || box_empty(tris + i)) return;
  global const tri_t* r = tris + i;
  for (int ty = r->min_y / TILE; ty <= r->max_y / TILE; ++ty)
    for (int tx = r->min_x / TILE; tx <= r->max_x / TILE; ++tx) {
      uint tile = ty * tiles_x + tx;
      bins[tile_base[tile] + atomic_inc(cursor + tile)] = *r;
    }
}

// Work-group = tile (get_global_id(0) / GROUP), work-item = a BLOCK_W x BLOCK_H block of it.
__attribute__((reqd_work_group_size(GROUP, 1, 1))) kernel void raster_gpu_tiles(
    global const tri_t* bins, global const ulong* tile_base, uint tiles_x, uint width, uint height,
    global float* depth_out
#ifdef WRITE_ID
    ,
    global uint* id_out
#endif
) {
  local tri_t batch[GROUP];
  uint tile = get_global_id(0) / GROUP, lid = get_local_id(0);
  int bx0 = (tile % tiles_x) * TILE + (lid % ITEMS_X) * BLOCK_W;
  int by0 = (tile / tiles_x) * TILE + (lid / ITEMS_X) * BLOCK_H;
  float depth[BLOCK_W * BLOCK_H];
#ifdef WRITE_ID
  uint ids[BLOCK_W * BLOCK_H];
#endif
#pragma unroll
  for (int i = 0; i < BLOCK_W * BLOCK_H; ++i) {
    depth[i] = 1.0f;
#ifdef WRITE_ID
    ids[i] = 0xffffffffu;
#endif
  }
#if HIZ
  float block_far = 1.0f;  // no texel of the block is deeper
#endif
  const ulong first = tile_base[tile], end = tile_base[tile + 1];
  for (ulong base = first; base < end; base += GROUP) {
    uint n = (uint)min((ulong)GROUP, end - base);
    barrier(CLK_LOCAL_MEM_FENCE);  // the last batch is done with
    if (lid < n) batch[lid] = bins[base + lid];
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint k = 0; k < n; ++k) {
      local const tri_t* r = batch + k;
      int x_lo = max((int)r->min_x, bx0), x_hi = min((int)r->max_x, bx0 + BLOCK_W - 1);
      int y_lo = max((int)r->min_y, by0), y_hi = min((int)r->max_y, by0 + BLOCK_H - 1);
      if (x_lo > x_hi || y_lo > y_hi) continue;
      float fx0 = r->x0 / SUBPIXEL, fy0 = r->y0 / SUBPIXEL;
#if HIZ
      if (block_far < 1.0f &&
          plane_behind(r->z0, r->dzdx, r->dzdy, fx0, fy0, x_lo, x_hi, y_lo, y_hi, block_far))
        continue;
#endif
      // Edge functions at the block's first pixel centre and their steps per pixel: exact in 64
      // bits (raster.cl's reasoning), so coverage is raster.cl's to the last pixel.
      long px = ((long)bx0 << SUBPIXEL_BITS) + 128, py = ((long)by0 << SUBPIXEL_BITS) + 128;
      long e0 = edge(r->x1, r->y1, r->x2, r->y2, px, py) + fill_bias(r->x1, r->y1, r->x2, r->y2);
      long e1 = edge(r->x2, r->y2, r->x0, r->y0, px, py) + fill_bias(r->x2, r->y2, r->x0, r->y0);
      long e2 = edge(r->x0, r->y0, r->x1, r->y1, px, py) + fill_bias(r->x0, r->y0, r->x1, r->y1);
      long sx0 = (long)(r->y1 - r->y2) * 256, sy0 = (long)(r->x2 - r->x1) * 256;
      long sx1 = (long)(r->y2 - r->y0) * 256, sy1 = (long)(r->x0 - r->x2) * 256;
      long sx2 = (long)(r->y0 - r->y1) * 256, sy2 = (long)(r->x1 - r->x0) * 256;
      bool whole = true;  // the record covers every texel of the block
#pragma unroll
      for (int j = 0; j < BLOCK_H; ++j) {
        int y = by0 + j;
        float zrow = plane_row(r->z0, r->dzdy, fy0, y);
#pragma unroll
        for (int i = 0; i < BLOCK_W; ++i) {
          int x = bx0 + i;
          bool in =
              x >= x_lo && x <= x_hi && y >= y_lo && y <= y_hi &&
              ((e0 + i * sx0 + j * sy0) | (e1 + i * sx1 + j * sy1) | (e2 + i * sx2 + j * sy2)) >= 0;
          whole = whole && in;
          float z = plane_at(zrow, r->dzdx, fx0, x);
          DEPTH_WRITE(j * BLOCK_W + i, in, z, r->prim)
        }
      }
#if HIZ
      if (whole) {
        block_far = 0.0f;
#pragma unroll
        for (int i = 0; i < BLOCK_W * BLOCK_H; ++i) block_far = fmax(block_far, depth[i]);
      }
#endif
    }
  }
#pragma unroll
  for (int j = 0; j < BLOCK_H; ++j)
#pragma unroll
    for (int i = 0; i < BLOCK_W; ++i) {
      int x = bx0 + i, y = by0 + j;
      if (x >= (int)width || y >= (int)height) continue;
      size_t o = (size_t)y * width + x;
      depth_out[o] = depth[j * BLOCK_W + i];
#ifdef WRITE_ID
      id_out[o] = ids[j * BLOCK_W + i];
#endif
    }
}
