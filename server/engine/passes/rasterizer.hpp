// The depth rasterizer (kernels/rasterizer.cl): draws -> a depth buffer and, optionally, the id
// of the nearest primitive per pixel. Shared by shadow maps and the camera view.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/device_types.hpp"
#include "engine/light/virtual_levels.hpp"  // kPageTexels
#include "engine/passes/light_args.hpp"
#include "engine/passes/scene_buffers.hpp"
#include "engine/passes/step_cache.hpp"
#include "engine/plan/cost.hpp"  // RasterLoad

namespace shadow {

// The draws of every instance that `include` accepts, through `world_to_ndc`. Primitive ids
// number the draws' triangles consecutively in this order.
template <typename Include>
std::vector<DrawItem> make_draws(const Scene& scene, const SceneBuffers& buffers,
                                 const glm::mat4& world_to_ndc, Include include) {
  std::vector<DrawItem> draws;
  uint32_t vertices = 0, triangles = 0;
  for (uint32_t j = 0; j < scene.instances.size(); ++j) {
    const Instance& inst = scene.instances[j];
    if (!include(inst)) continue;
    const MeshRange& m = buffers.meshes()[inst.mesh];
    DrawItem d{};
    d.to_clip = world_to_ndc * inst.transform;
    d.to_world = inst.transform;
    d.vertex_base = m.vertex_base;
    d.index_base = m.index_base;
    d.vertex_count = m.vertex_count;
    d.triangle_count = m.triangle_count;
    d.out_vertex_base = vertices;
    d.out_triangle_base = triangles;
    d.instance = j;
    d.flags = inst.receives_shadows ? kDrawReceives : 0u;
    if (inst.receiver_class != Instance::kNoClass)
      d.flags |= (inst.receiver_class + 1) << kDrawClassShift;
    vertices += m.vertex_count;
    triangles += m.triangle_count;
    draws.push_back(d);
  }
  return draws;
}

// The world-space caster bias of a light's map (Kozlov 14.3.1; ShadowMapSettings
// bias_world_constant / bias_world_texel), applied per vertex by transform_vertices. The
// default (0, 0) leaves vertices where they are (the camera view, unbiased maps).
struct WorldBias {
  glm::mat4 world_to_ndc{1.0f};
  LightItem light{};      // directional: along light.axis; spot, point: from light.position
  float constant = 0.0f;  // a, world units
  float texel = 0.0f;     // b, in world-space texels
  uint32_t map_size = 1;
};

// One pass's device buffers, kept between requests and grown when a request needs more.
struct RasterOutput {
  cl::Buffer depth;  // width * height floats, texture NDC z, 1.0 where empty
  cl::Buffer ids;    // width * height primitive ids (0xffffffff where empty), if asked for
  cl::Buffer draws;  // the uploaded draws, for passes that resolve ids
  // Intermediate results.
  cl::Buffer clip, tris, extra, counts, tile_total, tile_base, box_pixels, bins, load_partials;
  RasterLoad load;  // the run's, as binning counted it
  // Counts the runs that wrote `depth` (and `ids`): the keys of the steps that derive from an
  // output (the G-buffer resolve, the CSM basis, the atlas) name the result by it.
  uint64_t version = 0;
};

// Kernel paths that change speed only, never a result (each is checked against the plain path
// by raster_test); the ones that won on the bench are on by default. The GPU shape
// (the _gpu kernels) takes only `hiz`; the others are the CPU shape's.
struct RasterPaths {
  bool full_tile = true;     // a triangle covering a whole tile writes its depth plane in rows
  bool small32 = true;       // triangles under 64 pixels across: 32-bit edge functions
  bool point = true;         // triangles that may cover one pixel centre: one test, no loops
  bool vector_setup = true;  // set-up of unclipped triangles in a loop that vectorizes
  // Skip triangles behind everything a tile already holds. Off: a per-tile bound only helps
  // where a triangle covering the tile comes before the ones it hides, and it cost 5-40% of
  // the raster kernel on the bench's scenes (ground first) - docs/benchmarks.md.
  bool hiz = false;
  bool bin_by_chunk = true;  // each binning work-item's counters contiguous
};

// The raster step's key (engine/passes/step_cache.hpp): everything its output depends on, the
// scene's device copy (SceneBuffers::id), the draws (matrices and instances), the size, the ids,
// the world-space bias and the kernels' build options (profile and paths). Bits, not values: -0 and
// 0 differ.
uint64_t raster_key(uint64_t scene, const std::vector<DrawItem>& draws, uint32_t width,
                    uint32_t height, bool write_ids, const WorldBias& bias,
                    const std::string& options);

// A virtual level's pages as the raster's target (issue 53; rasterizer.cl's PAGED): the map is
// the level's square window, and only the tiles whose 128^2 page has a slot in `table` (from entry
// `first`, row-major) are binned and drawn, each into its slot of `pool`: the `count` (slot, page)
// pairs of `draws` from `draw_first`.
struct PageTarget {
  const cl::Buffer* table = nullptr;
  uint32_t first = 0;
  const cl::Buffer* pool = nullptr;
  const cl::Buffer* draws = nullptr;
  uint32_t draw_first = 0, count = 0;
  glm::ivec4 tiles{0};  // the level's pages' bounding box in tiles (x0, y0, x1, y1, inclusive)
};

class Rasterizer {
 public:
  static constexpr uint32_t kTile = 64;

  Rasterizer(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // Runs transform, setup, binning and tile rasterization; `pass` prefixes the timing names and
  // names the buffer set, which stays valid until the next run of the same pass. A request too
  // big for the device's buffers throws ResourceExhausted naming `size_field`. A pass whose
  // output holds the result of the same inputs (the step cache's key: the scene, the draws, the
  // size, the ids, the bias and the build options) is not run again while the cache keeps.
  // With `pages`, the depths go to the pages' slots instead of the output's `depth` (never kept
  // by the step cache: pages have their own validity).
  const RasterOutput& run(const SceneBuffers& scene, const std::vector<DrawItem>& draws,
                          uint32_t width, uint32_t height, bool write_ids, const std::string& pass,
                          const std::string& size_field, Timeline& timeline,
                          const WorldBias& bias = WorldBias{}, const PageTarget* pages = nullptr);

  // What rasterizing `draws` at size x size and at each edge halved up to levels - 1 times
  // (levels <= kMaxLoadLevels) would load the raster with, without rasterizing: transform and
  // set-up at size x size, then raster_load, summed on the host per level. `pass` names its
  // timings; every measure shares one buffer set, and nothing is kept.
  static constexpr uint32_t kMaxLoadLevels = 4;  // MAX_LOAD_LEVELS in rasterizer.cl
  std::vector<RasterLoad> load(const SceneBuffers& scene, const std::vector<DrawItem>& draws,
                               uint32_t size, uint32_t levels, const std::string& pass,
                               Timeline& timeline);

  void warm_up();  // builds both program variants

  // For benches and tests; a change of paths builds (once) another program variant.
  void set_paths(const RasterPaths& paths) { paths_ = paths; }

  // The workspace's step cache, which decides whether a pass's output may be kept (none: never).
  void set_cache(StepCache* cache) { cache_ = cache; }
  StepCache* cache() const { return cache_; }

  // The request's cost limit in estimated ms (engine/plan/cost.hpp; 0: none), checked against the
  // triangle-tile overlaps after binning, before the raster pass.
  void set_max_cost_ms(double ms) { max_cost_ms_ = ms; }

 private:
  // The device profile's shape (issue 42): rasterizer.cl's CPU kernels, or its _gpu binning
  // and tiles after the same transform and set-up run a work-item per vertex and triangle.
  bool gpu_shape() const;
  size_t group() const;  // work-items per work-group: the profile's on the GPU shape, else 1
  std::string options(bool write_ids) const;
  struct BinChunks {
    uint32_t chunks, chunk_size;
  };
  // What set_up() wrote: a record slot per input triangle, room for `capacity` records in all.
  // How many there are (the clipped triangles' extra fans) stays on the device (out.extra): the
  // kernels after it read it there (rasterizer.cl's record_count), and the host reads the
  // records wanted with its one read of binning's totals or the load, setting up again with
  // room for them where they did not fit.
  struct Records {
    uint32_t triangles, capacity;
  };
  static BinChunks bin_chunks(uint32_t records, uint32_t tiles);
  // The kernels' page table and depth target: a level's (PageTarget), or none and the output's
  // depth.
  struct Pages {
    const cl::Buffer* table;
    uint32_t first;
    const cl::Buffer* depth;
    const cl::Buffer* draws;
    uint32_t draw_first, count;
    glm::ivec4 tiles;  // binning keeps to them
    bool paged;
    // The raster's work: every tile of a dense map, the slots' tiles of a level's pages.
    uint32_t drawn_tiles(uint32_t tiles) const {
      return paged ? count * (kPageTexels / kTile) * (kPageTexels / kTile) : tiles;
    }
  };
  // Binning up to the tiles' first entries; totals = {triangle-tile overlaps, box pixels,
  // records wanted}.
  void bin_cpu(Records records, uint32_t tiles_x, uint32_t tiles_y, const Pages& pages,
               const std::string& opts, const std::string& pass, RasterOutput& out,
               Timeline& timeline, uint64_t totals[3]);
  void bin_gpu(Records records, uint32_t tiles_x, uint32_t tiles_y, const Pages& pages,
               const std::string& opts, const std::string& pass, RasterOutput& out,
               Timeline& timeline, uint64_t totals[3]);
  // The records into out.bins, then the tiles into out.depth (and out.ids).
  void scatter_and_raster_cpu(Records records, uint32_t tiles_x, uint32_t tiles_y, uint32_t width,
                              uint32_t height, bool write_ids, const Pages& pages,
                              const std::string& opts, const std::string& pass, RasterOutput& out,
                              Timeline& timeline);
  void scatter_and_raster_gpu(Records records, uint32_t tiles_x, uint32_t width, uint32_t height,
                              bool write_ids, const Pages& pages, const std::string& opts,
                              const std::string& pass, RasterOutput& out, Timeline& timeline);
  // Transform and set-up into `out`'s buffers with room for `capacity` records (at least the
  // input triangles; 0: a few more than that; past 32-bit record indices refused), without
  // waiting for them.
  Records set_up(const SceneBuffers& scene, const std::vector<DrawItem>& draws, uint32_t width,
                 uint32_t height, uint64_t capacity, const std::string& opts,
                 const std::string& pass, RasterOutput& out, Timeline& timeline,
                 const WorldBias& bias);

  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  std::map<std::string, RasterOutput> buffers_;  // by pass as the timeline names it
  // load()'s, one set for every measure whatever its pass (nothing is kept between them), so a
  // goal's measures over many lights and techniques hold one scene's set-up at a time.
  RasterOutput load_buffers_;
  cl::Buffer no_pages_;  // dense maps' page table argument
  double max_cost_ms_ = 0;
  RasterPaths paths_;
  StepCache* cache_ = nullptr;
};

}  // namespace shadow
