// Shadow atlases (kernels/atlas.cl): the receiving instances' surfaces in their UV tiles as a
// G-buffer for the visibility passes, and the gutter of the result.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/device_types.hpp"
#include "engine/passes/device_texture.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/scene_buffers.hpp"
#include "engine/passes/step_cache.hpp"
#include "engine/plan/atlas_layout.hpp"

namespace shadow {

class AtlasPass {
 public:
  AtlasPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // Uploads the receiving meshes' UVs and rasterizes every receiving instance into its tile
  // (atlas_layout()); throws InvalidArgument naming the mesh whose UVs leave [0, 1] or overlap.
  // Valid until the next bake.
  const GBuffer& bake(const RenderRequest& request, const SceneBuffers& buffers,
                      Timeline& timeline);
  // Every receiving instance in a tile of settings.tile texels (> 0).
  const GBuffer& bake(const Scene& scene, const SceneBuffers& buffers,
                      const AtlasSettings& settings, Timeline& timeline);
  const GBuffer& bake(const Scene& scene, const SceneBuffers& buffers, const AtlasLayout& layout,
                      uint32_t gutter, Timeline& timeline);
  // The visibility of the baked texels, copied out of `visibility` (a visibility pass's buffer)
  // with `gutter` texels dilated around the charts, kept for `slot` (the light's pass prefix)
  // until its next finish or the next bake.
  const cl::Buffer& finish(const cl::Buffer& visibility, uint32_t gutter, const std::string& slot,
                           Timeline& timeline);
  // The slot's last finish() result (the step cache decides when it may be taken).
  const cl::Buffer& result(const std::string& slot) {
    Slot& s = slots_[slot];
    return s.dilated[s.result];
  }
  // Counts the bakes: the keys of the steps that read the bake name it by this.
  uint64_t bake_version() const { return bake_version_; }
  // The UVs of each corner of mesh `range`'s triangles (3 float2 a triangle), from the last bake's
  // upload. Valid until the next call.
  const cl::Buffer& corner_uvs(const SceneBuffers& buffers, const MeshRange& range,
                               Timeline& timeline);
  // `atlas` (a finish() result) as two channels, the visibility at surface texels (0 at empty and
  // gutter texels) and their coverage, for its summed-area table. Valid until the next call.
  DeviceTexture coverage(const cl::Buffer& atlas, Timeline& timeline);
  // The workspace's step cache: the bake is kept while the receiving instances stay where they
  // were in the same tiles (none: never).
  void set_cache(StepCache* cache) { cache_ = cache; }
  // The slot's penumbra per atlas texel (the atlas filters': PcssPass::penumbra writes it), kept
  // with the slot's result.
  cl::Buffer& penumbra(const std::string& slot) { return slots_[slot].penumbra; }
  // The slot's soft atlas (the atlas filters': AtlasSoftenPass::soften writes it), kept with the
  // slot's result.
  cl::Buffer& soft(const std::string& slot) { return slots_[slot].soft; }

  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  const std::vector<AtlasTile>& tiles() const { return tiles_; }
  // The bake's uploads, for lookups into the atlas: the scene's UVs in vertex order, and a uint4
  // per scene instance (x, y, size of its tile, 1 if it has one).
  const cl::Buffer& uvs() const { return uvs_; }
  const cl::Buffer& instance_tiles() const { return instance_tiles_; }
  // Each baked texel's axes on the surface (NaN where empty): the world offsets of one texel
  // step along the atlas' x and y, in the tangents of its normal (surface_tangents in
  // prelude.cl) as (x.t1, x.t2, y.t1, y.t2); the atlas filters map a penumbra through them.
  const cl::Buffer& texel_axes() const { return texel_axes_; }
  // Each texel's chart (an integer >= 1 as a float, 0 where empty): the atlas filters keep to
  // the chart of the texel they filter for.
  const cl::Buffer& texel_charts() const { return charts_[0]; }
  // The largest tile.
  uint32_t tile() const { return tile_; }
  // Each texel's tile: per cell of cell() x cell() texels (width() / cell() a row) the tile over
  // it as a uint4 (x, y, size, 1), zeros where none is (tile_cells()).
  const cl::Buffer& tile_cells() const { return cells_; }
  uint32_t cell() const { return cell_; }
  void warm_up();

 private:
  // atlas.cl's kernel `name` in the device profile's shape (pixel_shape.hpp), and a launch over
  // `count` triangles or texels: chunks of `chunk` per work-item on the CPU shape, one on the GPU.
  cl_kernel kernel(const char* name);
  cl::Events launch(cl_kernel kernel, uint32_t count, uint32_t chunk) const;
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  GBuffer view_;
  cl::Buffer uvs_, draws_, tiles_buffer_, instance_tiles_, owner_, inside_, flags_, coverage_,
      corners_, texel_axes_, chart_of_, cells_;
  // Each texel's chart: the surface's ([0]) and, dilated over the gutter, [gutter_charts_].
  cl::Buffer charts_[3];
  int gutter_charts_ = 0;
  // Per light (slot): the gutter's two buffers and which holds the result.
  struct Slot {
    cl::Buffer dilated[2], penumbra, soft;
    int result = 0;
  };
  std::map<std::string, Slot> slots_;
  StepCache* cache_ = nullptr;
  uint64_t bake_version_ = 0;
  uint32_t width_ = 0, height_ = 0, tile_ = 0, cell_ = 0;
  std::vector<AtlasTile> tiles_;
  // What the bake's asynchronous writes read, kept until they are done.
  struct {
    std::vector<float> uvs;
    std::vector<DrawItem> draws;
    std::vector<glm::uvec4> tiles, instance_tiles, cells;
    std::vector<uint32_t> chart_of;
    std::array<uint32_t, 3> flags;
  } staged_;
};

}  // namespace shadow
