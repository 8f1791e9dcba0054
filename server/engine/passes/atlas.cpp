#include "engine/passes/atlas.hpp"

#include <array>
#include <cstring>

#include "engine/passes/pixel_shape.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/plan/atlas_layout.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

constexpr uint32_t kTriangleChunk = 64, kTexelChunk = 256;  // as in atlas.cl
constexpr uint32_t kNone = 0xffffffffu;
// Charts are numbered 1 .. kChartIds within the atlas (repeating past it), small enough that the
// chart moments' sums stay exact in double (atlas_chart_moments).
constexpr uint32_t kChartIds = 2047;

}  // namespace

void AtlasPass::warm_up() {
  for (const char* k : {"atlas_cover", "atlas_resolve", "atlas_dilate", "atlas_dilate_charts",
                        "atlas_coverage", "atlas_corner_uvs"})
    kernel(k);
}

cl_kernel AtlasPass::kernel(const char* name) {
  return kernels_.kernel("atlas.cl", name, pixel_shape(runtime_, kTexelChunk).options);
}

cl::Events AtlasPass::launch(cl_kernel kernel, uint32_t count, uint32_t chunk) const {
  const PixelShape shape = pixel_shape(runtime_, chunk);
  return runtime_.launch(kernel, shape.work_items(count), shape.group);
}

const GBuffer& AtlasPass::bake(const RenderRequest& request, const SceneBuffers& buffers,
                               Timeline& timeline) {
  return bake(*request.scene, buffers, atlas_layout(request), request.atlas.gutter, timeline);
}

const GBuffer& AtlasPass::bake(const Scene& scene, const SceneBuffers& buffers,
                               const AtlasSettings& settings, Timeline& timeline) {
  std::vector<uint32_t> sizes(scene.instances.size(), 0);
  for (size_t i = 0; i < sizes.size(); ++i)
    if (scene.instances[i].receives_shadows) sizes[i] = settings.tile;
  return bake(scene, buffers, pack_atlas(sizes), settings.gutter, timeline);
}

const GBuffer& AtlasPass::bake(const Scene& scene, const SceneBuffers& buffers,
                               const AtlasLayout& layout, uint32_t gutter, Timeline& timeline) {
  // The same receivers where they were, in the same tiles: the same bake (with the default
  // density the tiles follow the lights).
  uint64_t key = 0;
  if (cache_ && cache_->keeping()) {
    const std::vector<DrawItem> draws = make_draws(
        scene, buffers, glm::mat4(1.0f), [](const Instance& i) { return i.receives_shadows; });
    StepKey k;
    k.add(buffers.id()).add(gutter).add(layout.tiles.size());
    for (const AtlasTile& a : layout.tiles) k.add(a.instance).add(a.x).add(a.y).add(a.size);
    key = k.bytes(draws.data(), draws.size() * sizeof(DrawItem)).value();
    if (cache_->take("atlas.bake", key, "atlas.bake", timeline)) return view_;
  }
  ++bake_version_;
  tiles_ = layout.tiles;
  width_ = uint32_t(layout.size.width), height_ = uint32_t(layout.size.height);
  tile_ = layout.largest, cell_ = layout.cell;
  const uint32_t texels = width_ * height_;
  // Each cell's tile, for the kernels that keep to a texel's tile.
  staged_.cells = shadow::tile_cells(layout);
  runtime_.ensure(cells_, std::max<size_t>(staged_.cells.size(), 1) * sizeof(glm::uvec4));
  timeline.add("atlas.upload", runtime_.write(cells_, staged_.cells.data(),
                                              staged_.cells.size() * sizeof(glm::uvec4)));

  // The UVs in the scene's vertex order; meshes that receive nothing keep zeros.
  const MeshRange& last = buffers.meshes().back();
  std::vector<float>& uvs = staged_.uvs;  // members: the writes below finish asynchronously
  uvs.assign((size_t{last.vertex_base} + last.vertex_count) * 2, 0.0f);
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    if (!scene.meshes[m].uvs.empty())
      std::memcpy(uvs.data() + size_t{buffers.meshes()[m].vertex_base} * 2,
                  scene.meshes[m].uvs.data(), scene.meshes[m].uvs.size() * sizeof(float));
  runtime_.ensure(uvs_, uvs.size() * sizeof(float) + sizeof(float));
  timeline.add("atlas.upload", runtime_.write(uvs_, uvs.data(), uvs.size() * sizeof(float)));

  // The receiving instances in tile order, with their tiles.
  std::vector<DrawItem>& draws = staged_.draws;
  draws = make_draws(scene, buffers, glm::mat4(1.0f),
                     [](const Instance& i) { return i.receives_shadows; });
  std::vector<glm::uvec4>& tiles = staged_.tiles;
  tiles.clear();
  staged_.instance_tiles.assign(scene.instances.size(), glm::uvec4(0));
  for (const AtlasTile& t : tiles_) {
    tiles.emplace_back(t.x, t.y, t.size, 0u);
    staged_.instance_tiles[t.instance] = glm::uvec4(t.x, t.y, t.size, 1u);
  }
  runtime_.ensure(instance_tiles_, staged_.instance_tiles.size() * sizeof(glm::uvec4));
  timeline.add("atlas.upload", runtime_.write(instance_tiles_, staged_.instance_tiles.data(),
                                              staged_.instance_tiles.size() * sizeof(glm::uvec4)));
  const uint32_t triangles =
      draws.empty() ? 0 : draws.back().out_triangle_base + draws.back().triangle_count;
  // Each triangle's chart, numbered across the tiles so that neighbouring tiles' charts differ.
  std::vector<uint32_t>& chart_of = staged_.chart_of;
  chart_of.assign(size_t{triangles} + 1, 0u);
  std::map<uint32_t, UvCharts> charts_of_mesh;
  uint64_t next_chart = 0;
  for (const DrawItem& d : draws) {
    const uint32_t mesh = scene.instances[d.instance].mesh;
    auto it = charts_of_mesh.find(mesh);
    if (it == charts_of_mesh.end())
      it = charts_of_mesh.emplace(mesh, uv_charts(scene.meshes[mesh])).first;
    for (uint32_t t = 0; t < d.triangle_count; ++t)
      chart_of[d.out_triangle_base + t] =
          uint32_t(1 + (next_chart + it->second.of_triangle[t]) % kChartIds);
    next_chart += it->second.count;
  }
  runtime_.ensure(chart_of_, chart_of.size() * sizeof(uint32_t));
  timeline.add("atlas.upload",
               runtime_.write(chart_of_, chart_of.data(), chart_of.size() * sizeof(uint32_t)));
  runtime_.ensure(draws_, draws.size() * sizeof(DrawItem));
  runtime_.ensure(tiles_buffer_, tiles.size() * sizeof(glm::uvec4));
  timeline.add("atlas.upload",
               runtime_.write(draws_, draws.data(), draws.size() * sizeof(DrawItem)));
  timeline.add("atlas.upload",
               runtime_.write(tiles_buffer_, tiles.data(), tiles.size() * sizeof(glm::uvec4)));

  runtime_.ensure(owner_, size_t{texels} * sizeof(uint32_t));
  runtime_.ensure(inside_, size_t{texels} * sizeof(uint32_t));
  runtime_.ensure(flags_, 3 * sizeof(uint32_t));
  staged_.flags = {kNone, 0u, kNone};  // bad triangle, overlaps, first overlap
  timeline.add("atlas.cover", runtime_.fill(owner_, kNone));
  timeline.add("atlas.cover", runtime_.fill_zero(inside_));
  timeline.add("atlas.cover", runtime_.write(flags_, staged_.flags.data(), 3 * sizeof(uint32_t)));

  const uint32_t draw_count = uint32_t(draws.size());
  cl_kernel cover = kernel("atlas_cover");
  cl::set_args(cover, buffers.indices(), uvs_, draws_, draw_count, tiles_buffer_, triangles, width_,
               owner_, inside_, flags_);
  timeline.add("atlas.cover", launch(cover, triangles, kTriangleChunk));

  runtime_.ensure(view_.position, size_t{texels} * 3 * sizeof(float));
  runtime_.ensure(view_.normal, size_t{texels} * 4 * sizeof(float));
  runtime_.ensure(texel_axes_, size_t{texels} * 4 * sizeof(float));
  for (cl::Buffer& b : charts_) runtime_.ensure(b, size_t{texels} * sizeof(float));
  cl_kernel resolve = kernel("atlas_resolve");
  cl::set_args(resolve, buffers.positions(), buffers.indices(), uvs_, draws_, draw_count,
               tiles_buffer_, owner_, inside_, chart_of_, texels, width_, view_.position,
               view_.normal, texel_axes_, charts_[0], flags_);
  timeline.add("atlas.resolve", launch(resolve, texels, kTexelChunk));
  // The gutter's charts (finish() fills each gutter texel from one chart): charts_[0] keeps the
  // surface's, charts_[1] and [2] ping-pong.
  gutter_charts_ = 0;
  if (gutter > 0) {
    cl_kernel dilate = kernel("atlas_dilate_charts");
    for (uint32_t i = 0; i < gutter; ++i) {
      const int src = gutter_charts_, dst = 1 + int(i % 2);
      cl::set_args(dilate, charts_[src], texels, width_, cells_, cell_, charts_[dst]);
      timeline.add("atlas.gutter", launch(dilate, texels, kTexelChunk));
      gutter_charts_ = dst;
    }
  }

  std::array<uint32_t, 3> found{};
  timeline.add("atlas.resolve", runtime_.read(flags_, found.data(), sizeof found));
  runtime_.finish();
  const auto mesh_of_triangle = [&](uint32_t t) {
    size_t d = 0;
    while (d + 1 < draws.size() && draws[d + 1].out_triangle_base <= t) ++d;
    return std::array<uint32_t, 2>{draws[d].instance, scene.instances[draws[d].instance].mesh};
  };
  if (found[0] != kNone) {
    const auto [instance, mesh] = mesh_of_triangle(found[0]);
    throw InvalidArgument("scene.meshes[" + std::to_string(mesh) + "].uvs",
                          "UVs outside [0, 1] or not finite (instance " + std::to_string(instance) +
                              "); the shadow atlas needs each mesh's UVs in [0, 1]");
  }
  if (found[1] != 0) {
    const uint32_t x = found[2] % width_, y = found[2] / width_;
    AtlasTile in{};
    for (const AtlasTile& t : tiles_)
      if (x >= t.x && x < t.x + t.size && y >= t.y && y < t.y + t.size) in = t;
    const uint32_t instance = in.instance, mesh = scene.instances[instance].mesh;
    throw InvalidArgument("scene.meshes[" + std::to_string(mesh) + "].uvs",
                          "UV triangles overlap (" + std::to_string(found[1]) +
                              " texels covered twice over the atlas; the first at uv (" +
                              std::to_string((x - in.x + 0.5) / std::max(in.size, 1u)) + ", " +
                              std::to_string((y - in.y + 0.5) / std::max(in.size, 1u)) +
                              ") in instance " + std::to_string(instance) + "'s tile of " +
                              std::to_string(in.size) + "x" + std::to_string(in.size) +
                              " texels): the shadow atlas needs a unique layout (mirrored or tiled "
                              "UVs are not one)");
  }
  if (cache_) cache_->made("atlas.bake", key);
  return view_;
}

const cl::Buffer& AtlasPass::finish(const cl::Buffer& visibility, uint32_t gutter,
                                    const std::string& slot, Timeline& timeline) {
  Slot& s = slots_[slot];
  const uint32_t texels = width_ * height_;
  for (cl::Buffer& b : s.dilated) runtime_.ensure(b, size_t{texels} * sizeof(float));
  cl_kernel dilate = kernel("atlas_dilate");
  // The first step copies out of the pass's buffer; the others ping-pong.
  const cl::Buffer* src = &visibility;
  const uint32_t steps = std::max(gutter, 1u);
  for (uint32_t i = 0; i < steps; ++i) {
    const cl::Buffer& dst = s.dilated[i % 2];
    cl::set_args(dilate, *src, charts_[gutter_charts_], texels, width_, cells_, cell_,
                 int(gutter > 0), dst);
    timeline.add("atlas.gutter", launch(dilate, texels, kTexelChunk));
    src = &dst;
  }
  s.result = int((steps - 1) % 2);
  return *src;
}

DeviceTexture AtlasPass::coverage(const cl::Buffer& atlas, Timeline& timeline) {
  const uint32_t texels = width_ * height_;
  runtime_.ensure(coverage_, size_t{texels} * 2 * sizeof(float));
  cl_kernel k = kernel("atlas_coverage");
  cl::set_args(k, atlas, charts_[0], texels, coverage_);
  timeline.add("atlas.coverage", launch(k, texels, kTexelChunk));
  return DeviceTexture{&coverage_, width_, height_, 2};
}

const cl::Buffer& AtlasPass::corner_uvs(const SceneBuffers& buffers, const MeshRange& range,
                                        Timeline& timeline) {
  runtime_.ensure(corners_, size_t{range.triangle_count} * 6 * sizeof(float) + sizeof(float));
  cl_kernel k = kernel("atlas_corner_uvs");
  cl::set_args(k, buffers.indices(), uvs_, range.index_base, range.vertex_base,
               range.triangle_count, corners_);
  timeline.add("atlas.corner_uvs", launch(k, range.triangle_count, kTexelChunk));
  return corners_;
}

}  // namespace shadow
