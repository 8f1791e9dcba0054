#include "engine/passes/rasterizer.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "engine/passes/pixel_shape.hpp"
#include "engine/plan/cost.hpp"
#include "wire/errors.hpp"
#include "wire/units.hpp"

namespace shadow {
namespace {

constexpr uint32_t kVertexChunk = 1024, kTriangleChunk = 256;  // as in rasterizer.cl, CPU shape
constexpr uint32_t kTargetBinChunk = 2048;                     // records per binning work-item
constexpr uint32_t kLoadChunk = 4096, kMaxLoadChunks = 1024;   // raster_load's work-items

uint32_t ceil_div(uint64_t a, uint64_t b) {
  return static_cast<uint32_t>((a + b - 1) / b);
}

}  // namespace

uint64_t raster_key(uint64_t scene, const std::vector<DrawItem>& draws, uint32_t width,
                    uint32_t height, bool write_ids, const WorldBias& bias,
                    const std::string& options) {
  StepKey k;
  k.add(scene).add(draws.size()).bytes(draws.data(), draws.size() * sizeof(DrawItem));
  k.add(width).add(height).add(write_ids).add(options);
  k.add(bias.world_to_ndc).bytes(&bias.light, sizeof bias.light);  // LightItem: explicit padding
  return k.add(bias.constant).add(bias.texel).add(bias.map_size).value();
}

bool Rasterizer::gpu_shape() const {
  return runtime_.device_info().profile().shape == cl::KernelShape::kGpu;
}

size_t Rasterizer::group() const {
  return chunk_group(runtime_);
}

std::string Rasterizer::options(bool write_ids) const {
  std::string o = "-DTILE=" + std::to_string(kTile) + (write_ids ? " -DWRITE_ID" : "") +
                  " -DHIZ=" + std::to_string(int(paths_.hiz));
  if (gpu_shape())  // a vertex and a triangle per work-item; the GPU shape's work-groups
    return o + " -DVERTEX_CHUNK=1 -DTRIANGLE_CHUNK=1 -DVECTOR_SETUP=0 -DGROUP=" +
           std::to_string(group());
  return o + " -DFULL_TILE=" + std::to_string(int(paths_.full_tile)) +
         " -DSMALL32=" + std::to_string(int(paths_.small32)) +
         " -DPOINT_PATH=" + std::to_string(int(paths_.point)) +
         " -DVECTOR_SETUP=" + std::to_string(int(paths_.vector_setup)) +
         " -DBIN_BY_CHUNK=" + std::to_string(int(paths_.bin_by_chunk));
}

void Rasterizer::warm_up() {
  for (bool ids : {false, true}) {
    for (const char* k : {"transform_vertices", "setup_triangles", "raster_load"})
      kernels_.kernel("rasterizer.cl", k, options(ids));
    if (gpu_shape()) {
      for (const char* k : {"bin_gpu_count", "bin_gpu_scan", "bin_gpu_scatter", "raster_gpu_tiles"})
        kernels_.kernel("rasterizer.cl", k, options(ids));
    } else {
      for (const char* k :
           {"bin_count", "bin_scan_tiles", "bin_scan_totals", "bin_scatter", "raster_tiles"})
        kernels_.kernel("rasterizer.cl", k, options(ids));
    }
  }
  // Virtual maps' pages (issue 53), depth only: one program build.
  kernels_.kernel("rasterizer.cl", gpu_shape() ? "raster_gpu_tiles" : "raster_tiles",
                  options(false) + " -DPAGED");
}

Rasterizer::Records Rasterizer::set_up(const SceneBuffers& scene,
                                       const std::vector<DrawItem>& draws, uint32_t width,
                                       uint32_t height, uint64_t capacity, const std::string& opts,
                                       const std::string& pass, RasterOutput& out,
                                       Timeline& timeline, const WorldBias& bias) {
  const cl::Runtime& rt = runtime_;
  const uint32_t draw_count = static_cast<uint32_t>(draws.size());
  const uint32_t vertex_total =
      draws.empty() ? 0 : draws.back().out_vertex_base + draws.back().vertex_count;
  const uint32_t triangle_total =
      draws.empty() ? 0 : draws.back().out_triangle_base + draws.back().triangle_count;
  rt.ensure(out.draws, draws.size() * sizeof(DrawItem));
  timeline.add(pass + ".transform",
               rt.write(out.draws, draws.data(), draws.size() * sizeof(DrawItem)));

  rt.ensure(out.clip, size_t{vertex_total} * 4 * sizeof(float));
  const cl::Buffer& clip = out.clip;
  cl_kernel transform = kernels_.kernel("rasterizer.cl", "transform_vertices", opts);
  cl::set_args(transform, scene.positions(), out.draws, draw_count, vertex_total, clip,
               bias.world_to_ndc, bias.light, bias.constant, bias.texel,
               1.0f / float(bias.map_size));
  const uint32_t vertex_chunk = gpu_shape() ? 1 : kVertexChunk;
  timeline.add(pass + ".transform",
               rt.launch(transform, ceil_div(vertex_total, vertex_chunk), group()));

  // Set-up: record t belongs to triangle t; clipping appends the rare extra fan triangles
  // after them, counted in out.extra. Room for a few.
  if (capacity == 0) capacity = uint64_t{triangle_total} + triangle_total / 16 + 1024;
  if (capacity > std::numeric_limits<uint32_t>::max())
    throw ResourceExhausted("scene", pass + " sets up " + std::to_string(capacity) +
                                         " triangles after clipping, more than 2^32 - 1");
  const Records records{triangle_total, static_cast<uint32_t>(capacity)};
  rt.ensure(out.extra, sizeof(uint32_t));
  rt.ensure(out.tris, uint64_t{records.capacity} * kTriRecordBytes);
  timeline.add(pass + ".setup", rt.fill_zero(out.extra));
  cl_kernel setup = kernels_.kernel("rasterizer.cl", "setup_triangles", opts);
  cl::set_args(setup, scene.indices(), out.draws, draw_count, triangle_total, clip, float(width),
               float(height), records.capacity, out.tris, out.extra);
  const uint32_t triangle_chunk = gpu_shape() ? 1 : kTriangleChunk;
  timeline.add(pass + ".setup",
               rt.launch(setup, ceil_div(triangle_total, triangle_chunk), group()));
  return records;
}

std::vector<RasterLoad> Rasterizer::load(const SceneBuffers& scene,
                                         const std::vector<DrawItem>& draws, uint32_t size,
                                         uint32_t levels, const std::string& pass,
                                         Timeline& timeline) {
  if (levels == 0 || levels > kMaxLoadLevels || (size >> (levels - 1)) == 0)
    throw std::logic_error("Rasterizer::load: levels out of range");
  const std::string opts = options(false);
  RasterOutput& out = load_buffers_;
  const cl::Runtime& rt = runtime_;
  std::vector<uint64_t> partials;
  uint32_t chunks = 0;
  for (uint64_t capacity = 0;;) {
    const Records records =
        set_up(scene, draws, size, size, capacity, opts, pass, out, timeline, {});
    chunks = std::clamp(ceil_div(records.capacity, kLoadChunk), 1u, kMaxLoadChunks);
    const uint32_t chunk_size = std::max(1u, ceil_div(records.capacity, chunks));
    const size_t words = size_t{chunks} * levels * 2;
    rt.ensure(out.load_partials, (words + 1) * sizeof(uint64_t));
    cl_kernel kernel = kernels_.kernel("rasterizer.cl", "raster_load", opts);
    cl::set_args(kernel, out.tris, records.triangles, records.capacity, out.extra, chunk_size,
                 chunks, levels, out.load_partials);
    timeline.add(pass + ".load", rt.launch(kernel, chunks));
    partials.resize(words + 1);
    timeline.add(pass + ".load", rt.read(out.load_partials, partials.data(), (words + 1) * 8));
    if (partials[words] <= records.capacity) break;
    capacity = partials[words];  // rare: set up again with room for every record
  }
  std::vector<RasterLoad> load(levels);
  for (uint32_t c = 0; c < chunks; ++c)
    for (uint32_t k = 0; k < levels; ++k) {
      const size_t at = (size_t{c} * levels + k) * 2;
      load[k] += {partials[at], partials[at + 1]};
    }
  return load;
}

// The CPU shape's binning: a counting sort by chunks of records, each chunk's counters its own
// (rasterizer.cl). Chunks of about kTargetBinChunk records, at most kMaxBinCounters counters.
Rasterizer::BinChunks Rasterizer::bin_chunks(uint32_t records, uint32_t tiles) {
  const uint32_t max_chunks = static_cast<uint32_t>(std::max<uint64_t>(1, kMaxBinCounters / tiles));
  const uint32_t chunks = std::clamp(ceil_div(records, kTargetBinChunk), 1u, max_chunks);
  return {chunks, std::max(1u, ceil_div(records, chunks))};
}

void Rasterizer::bin_cpu(Records records, uint32_t tiles_x, uint32_t tiles_y, const Pages& pages,
                         const std::string& opts, const std::string& pass, RasterOutput& out,
                         Timeline& timeline, uint64_t totals[3]) {
  const cl::Runtime& rt = runtime_;
  const uint32_t tiles = tiles_x * tiles_y;
  // Chunks over the room set up, the records past the count left out (record_count).
  const auto [chunks, chunk_size] = bin_chunks(records.capacity, tiles);
  rt.ensure(out.counts, size_t{tiles} * chunks * sizeof(uint32_t));
  rt.ensure(out.tile_total, size_t{tiles} * sizeof(uint32_t));
  rt.ensure(out.tile_base, (size_t{tiles} + 3) * sizeof(uint64_t));
  rt.ensure(out.box_pixels, size_t{chunks} * sizeof(uint64_t));
  const cl::Buffer &counts = out.counts, &tile_total = out.tile_total, &tile_base = out.tile_base;
  cl_kernel bin_count = kernels_.kernel("rasterizer.cl", "bin_count", opts);
  cl::set_args(bin_count, out.tris, records.triangles, records.capacity, out.extra, chunk_size,
               chunks, tiles_x, tiles_y, counts, out.box_pixels, *pages.table, pages.first,
               pages.tiles);
  timeline.add(pass + ".bin", rt.launch(bin_count, chunks));
  cl_kernel scan_tiles = kernels_.kernel("rasterizer.cl", "bin_scan_tiles", opts);
  cl::set_args(scan_tiles, counts, chunks, tiles, tile_total);
  constexpr uint32_t kScanTiles = 64;  // SCAN_TILES in rasterizer.cl
  timeline.add(pass + ".bin",
               rt.launch(scan_tiles, paths_.bin_by_chunk ? ceil_div(tiles, kScanTiles) : tiles));
  cl_kernel scan_totals = kernels_.kernel("rasterizer.cl", "bin_scan_totals", opts);
  cl::set_args(scan_totals, tile_total, tiles, out.box_pixels, chunks, records.triangles, out.extra,
               tile_base);
  timeline.add(pass + ".bin", rt.launch(scan_totals, 1));
  timeline.add(pass + ".bin",
               rt.read(tile_base, totals, 3 * sizeof(uint64_t), size_t{tiles} * sizeof(uint64_t)));
}

void Rasterizer::scatter_and_raster_cpu(Records records, uint32_t tiles_x, uint32_t tiles_y,
                                        uint32_t width, uint32_t height, bool write_ids,
                                        const Pages& pages, const std::string& opts,
                                        const std::string& pass, RasterOutput& out,
                                        Timeline& timeline) {
  const cl::Runtime& rt = runtime_;
  const uint32_t tiles = tiles_x * tiles_y;
  const auto [chunks, chunk_size] = bin_chunks(records.capacity, tiles);
  cl_kernel scatter = kernels_.kernel("rasterizer.cl", "bin_scatter", opts);
  cl::set_args(scatter, out.tris, records.triangles, records.capacity, out.extra, chunk_size,
               chunks, tiles_x, tiles_y, out.counts, out.tile_base, out.bins, *pages.table,
               pages.first, pages.tiles);
  timeline.add(pass + ".bin", rt.launch(scatter, chunks));
  cl_kernel raster = kernels_.kernel("rasterizer.cl", "raster_tiles", opts);
  if (write_ids)
    cl::set_args(raster, out.bins, out.tile_base, tiles_x, width, height, *pages.draws,
                 pages.draw_first, out.depth, out.ids);
  else
    cl::set_args(raster, out.bins, out.tile_base, tiles_x, width, height, *pages.draws,
                 pages.draw_first, *pages.depth);
  if (pages.drawn_tiles(tiles) > 0)  // a level whose pages did not fit the pool has none
    timeline.add(pass + ".raster", rt.launch(raster, pages.drawn_tiles(tiles)));
}

// The GPU shape's binning (rasterizer.cl's bin_gpu_*): atomic counts per tile, then one
// work-group's scan. out.counts holds the tiles' counts, out.tile_total their cursors for the
// scatter, out.box_pixels the work-groups' box pixels.
void Rasterizer::bin_gpu(Records records, uint32_t tiles_x, uint32_t tiles_y, const Pages& pages,
                         const std::string& opts, const std::string& pass, RasterOutput& out,
                         Timeline& timeline, uint64_t totals[3]) {
  const cl::Runtime& rt = runtime_;
  const uint32_t tiles = tiles_x * tiles_y;
  // A work-item per record of the room set up, those past the count idle (record_count).
  const uint32_t groups = std::max(1u, ceil_div(records.capacity, group()));
  rt.ensure(out.counts, size_t{tiles} * sizeof(uint32_t));
  rt.ensure(out.tile_total, size_t{tiles} * sizeof(uint32_t));
  rt.ensure(out.tile_base, (size_t{tiles} + 3) * sizeof(uint64_t));
  rt.ensure(out.box_pixels, size_t{groups} * sizeof(uint64_t));
  timeline.add(pass + ".bin", rt.fill_zero(out.counts));
  timeline.add(pass + ".bin", rt.fill_zero(out.tile_total));
  cl_kernel count = kernels_.kernel("rasterizer.cl", "bin_gpu_count", opts);
  cl::set_args(count, out.tris, records.triangles, records.capacity, out.extra, tiles_x, out.counts,
               out.box_pixels, *pages.table, pages.first, pages.tiles);
  timeline.add(pass + ".bin", rt.launch(count, size_t{groups} * group(), group()));
  cl_kernel scan = kernels_.kernel("rasterizer.cl", "bin_gpu_scan", opts);
  cl::set_args(scan, out.counts, tiles, out.box_pixels, groups, records.triangles, out.extra,
               out.tile_base);
  timeline.add(pass + ".bin", rt.launch(scan, group(), group()));
  timeline.add(pass + ".bin",
               rt.read(out.tile_base, totals, 3 * sizeof(uint64_t), size_t{tiles} * 8));
}

void Rasterizer::scatter_and_raster_gpu(Records records, uint32_t tiles_x, uint32_t width,
                                        uint32_t height, bool write_ids, const Pages& pages,
                                        const std::string& opts, const std::string& pass,
                                        RasterOutput& out, Timeline& timeline) {
  const cl::Runtime& rt = runtime_;
  const uint32_t tiles = tiles_x * ceil_div(height, kTile);
  cl_kernel scatter = kernels_.kernel("rasterizer.cl", "bin_gpu_scatter", opts);
  cl::set_args(scatter, out.tris, records.triangles, records.capacity, out.extra, tiles_x,
               out.tile_total, out.tile_base, out.bins, *pages.table, pages.first, pages.tiles);
  timeline.add(
      pass + ".bin",
      rt.launch(scatter, size_t{std::max(1u, ceil_div(records.capacity, group()))} * group(),
                group()));
  cl_kernel raster = kernels_.kernel("rasterizer.cl", "raster_gpu_tiles", opts);
  if (write_ids)
    cl::set_args(raster, out.bins, out.tile_base, tiles_x, width, height, *pages.draws,
                 pages.draw_first, out.depth, out.ids);
  else
    cl::set_args(raster, out.bins, out.tile_base, tiles_x, width, height, *pages.draws,
                 pages.draw_first, *pages.depth);
  if (pages.drawn_tiles(tiles) > 0)
    timeline.add(pass + ".raster",
                 rt.launch(raster, size_t{pages.drawn_tiles(tiles)} * group(), group()));
}

const RasterOutput& Rasterizer::run(const SceneBuffers& scene, const std::vector<DrawItem>& draws,
                                    uint32_t width, uint32_t height, bool write_ids,
                                    const std::string& pass, const std::string& size_field,
                                    Timeline& timeline, const WorldBias& bias,
                                    const PageTarget* target) {
  const cl::Runtime& rt = runtime_;
  if (target && (write_ids || width != height || width % kPageTexels != 0))
    throw std::logic_error("Rasterizer::run: pages of a square window, depth only");
  const std::string opts = options(write_ids) + (target ? " -DPAGED" : "");
  const std::string slot = timeline.scoped(pass);
  RasterOutput& out = buffers_[slot];  // a light's own map
  uint64_t key = 0;
  if (cache_ && cache_->keeping() && !target) {  // pages are kept by their own stamps
    key = raster_key(scene.id(), draws, width, height, write_ids, bias, opts);
    if (cache_->take("raster:" + slot, key, pass, timeline)) return out;
  }
  ++out.version;
  rt.ensure(no_pages_, sizeof(uint32_t));  // dense maps' page table argument, never read
  const Pages pages =
      target
          ? Pages{target->table,      target->first, target->pool,  target->draws,
                  target->draw_first, target->count, target->tiles, true}
          : Pages{
                &no_pages_, 0, &out.depth, &no_pages_, 0, 0, glm::ivec4(0, 0, INT32_MAX, INT32_MAX),
                false};
  const uint32_t tiles_x = ceil_div(width, kTile), tiles_y = ceil_div(height, kTile);
  uint64_t totals[3] = {};  // overlaps, box pixels, records wanted
  Records records{};
  // One read a map, binning's totals, which size the bins; set-up's count stays on the device.
  for (uint64_t capacity = 0;;) {
    records = set_up(scene, draws, width, height, capacity, opts, pass, out, timeline, bias);
    if (gpu_shape())
      bin_gpu(records, tiles_x, tiles_y, pages, opts, pass, out, timeline, totals);
    else
      bin_cpu(records, tiles_x, tiles_y, pages, opts, pass, out, timeline, totals);
    if (totals[2] <= records.capacity) break;
    capacity = totals[2];  // rare: set up again with room for every record
  }
  out.load = {totals[0], totals[1]};
  const uint64_t entries = totals[0];
  if (entries > rt.max_alloc_bytes() / kTriRecordBytes) {
    throw ResourceExhausted(size_field, std::to_string(entries) +
                                            " triangle-tile overlaps need more than the device's " +
                                            std::to_string(rt.max_alloc_bytes()) +
                                            "-byte buffer limit; use a smaller size or fewer, "
                                            "smaller triangles");
  }
  const double raster_ms = raster_overlap_ms(entries);
  if (max_cost_ms_ > 0 && raster_ms > max_cost_ms_) {
    throw ResourceExhausted("request cost",
                            "rasterizing " + pass + " means " + std::to_string(entries) +
                                " triangle-tile overlaps, estimated at " + ms_text(raster_ms) +
                                ", over the server's limit of " + ms_text(max_cost_ms_) +
                                " (--max-request-cost): large triangles cost per 64x64 tile they "
                                "touch; use a smaller map or split them");
  }
  // The plan could not see them: the runtime guard holds the render to this figure too.
  rt.add_to_estimate(raster_ms);
  rt.ensure(out.bins, size_t{entries} * kTriRecordBytes);
  if (!target) rt.ensure(out.depth, size_t{width} * height * sizeof(float));
  if (write_ids) rt.ensure(out.ids, size_t{width} * height * sizeof(uint32_t));
  if (gpu_shape())
    scatter_and_raster_gpu(records, tiles_x, width, height, write_ids, pages, opts, pass, out,
                           timeline);
  else
    scatter_and_raster_cpu(records, tiles_x, tiles_y, width, height, write_ids, pages, opts, pass,
                           out, timeline);
  if (cache_) cache_->made("raster:" + slot, key);
  return out;
}

}  // namespace shadow
