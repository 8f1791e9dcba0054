// The workspace's step runners: one short function per StepKind, each over its pass, in one
// table. Workspace::run (workspace.cpp) walks the plan and calls them.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "engine/passes/step_cache.hpp"
#include "engine/plan/filter.hpp"
#include "engine/plan/light_request.hpp"
#include "engine/run/workspace.hpp"
#include "wire/errors.hpp"

namespace shadow {

Workspace::StepRunner Workspace::runner(StepKind kind) {
  // One runner per step kind, in StepKind's order.
  static constexpr std::pair<StepKind, StepRunner> kRunners[] = {
      {StepKind::kUploadScene, &Workspace::run_upload_scene},
      {StepKind::kCameraView, &Workspace::run_camera_view},
      {StepKind::kDepthRange, &Workspace::run_depth_range},
      {StepKind::kFitLight, &Workspace::run_fit_light},
      {StepKind::kVirtualPages, &Workspace::run_virtual_pages},
      {StepKind::kRenderMaps, &Workspace::run_render_maps},
      {StepKind::kBlurPlanes, &Workspace::run_blur_planes},
      {StepKind::kVisibility, &Workspace::run_visibility},
      {StepKind::kTexelDensity, &Workspace::run_texel_density},
      {StepKind::kMips, &Workspace::run_mips},
      {StepKind::kSat, &Workspace::run_sat},
      {StepKind::kCsmBasis, &Workspace::run_csm_basis},
      {StepKind::kAtlasView, &Workspace::run_atlas_view},
      {StepKind::kAtlasVisibility, &Workspace::run_atlas_visibility},
      {StepKind::kAtlasSoften, &Workspace::run_atlas_soften},
      {StepKind::kReadback, &Workspace::run_readback},
  };
  for (const auto& [k, run] : kRunners)
    if (k == kind) return run;
  throw std::logic_error("a step kind without a runner in kRunners");
}

DeviceTexture Workspace::source(const StepContext& s, Resource r) const {
  const uint32_t size = s.req.shadow_map.size;
  switch (r) {
    case Resource::kLightMaps:
      return DeviceTexture{&s.res.single_map->depth, size, size, 1};
    case Resource::kAtlas:
      return DeviceTexture{s.res.atlas, atlas.width(), atlas.height(), 1};
    default:
      return DeviceTexture{s.res.visibility, s.req.camera.width, s.req.camera.height, 1};
  }
}

void Workspace::run_upload_scene(StepContext& s) {
  if (scene_uploaded_)  // by the quality pick, in this timeline
    scene_uploaded_ = false;
  else
    upload_scene(s.req, s.control, cache.keeping(), s.pass, s.timeline);
}

void Workspace::run_camera_view(StepContext& s) {
  const GBuffer* probed = quality.take_view();
  s.shared.view =
      probed ? probed : &gbuffer.run(*s.req.scene, *scene_, s.req.camera, s.camera, s.timeline);
}

void Workspace::run_depth_range(StepContext& s) {
  if (std::optional<std::optional<DepthRange>> probed = quality.take_depth()) {
    s.shared.measured = *probed;  // the probe measured this very view
    s.timeline.reuse(s.pass);
  } else {
    s.shared.measured = depth_range.run(*s.shared.view, s.req.camera, s.timeline);
  }
}

void Workspace::run_fit_light(StepContext& s) {
  s.res.fit = fitter.fit(s.one, s.light, *scene_, s.shared.measured, s.shared.view, s.timeline);
  s.one.shadow_map.size = s.res.fit.map_size;  // AUTO's PSM cube: its faces'
  // Unrendered: texel density reads their matrices only.
  s.res.maps = fitter.draw(s.one, *scene_, s.res.fit, false, 0, s.timeline).maps;
}

// Marks the pages the view reads and gives them slots of the request's pool (begun by its first
// virtual light). Where they do not fit, the farthest pixels read coarser levels: the largest
// distance past which they do so that fits, found by bisection on its logarithm, or a refusal
// where the request asks for one or nothing fits. While the workspace keeps (a sequence), pages
// keep their texels from frame to frame: a change of the light, the scene's copy, the levels'
// depth or the world-space bias makes all of them stale, and a caster that moved the pages
// under its old and new boxes.
void Workspace::run_virtual_pages(StepContext& s) {
  const ShadowMapSettings& sm = s.one.shadow_map;
  const VirtualLevels& layout = *s.res.fit.virtual_levels;
  if (sm.virtual_pool_pages < layout.levels.size())
    throw InvalidArgument("shadow_map.virtual_pool_pages",
                          "must hold a page per level: this view's virtual map has " +
                              std::to_string(layout.levels.size()) + " levels, got " +
                              std::to_string(sm.virtual_pool_pages));
  if (!s.shared.virtual_pages) {
    virtual_pages.begin(sm.virtual_pool_pages, cache.keeping(), s.timeline);
    s.shared.virtual_pages = VirtualPageCounts{};
    s.shared.virtual_pages->pool_bytes = uint64_t{sm.virtual_pool_pages} * kPageBytes;
  }
  VirtualPageCounts& c = *s.shared.virtual_pages;
  const Camera& camera = s.req.camera;
  // PCSS reads a level whose texels hold its blocker search within kMaxSoftReach (pcss.cl).
  const bool soft = filter_facts(s.one.filter.kind).virtual_search;
  const float reach = float(virtual_reach(s.one.filter));
  const glm::vec4 search = soft ? pcss_search_bound(layout, only_light(s.one)) : glm::vec4(0.0f);
  VirtualMap* map = nullptr;
  const auto mark = [&](float coarsen_beyond) {
    map = &virtual_pages.mark(s.light, *s.shared.view, camera.width, s.pixels(), camera, layout,
                              sm.virtual_lod_bias, reach, s.timeline, coarsen_beyond, search);
    return virtual_pages.marked(*map, s.timeline);
  };
  const uint64_t room = sm.virtual_pool_pages - c.resident;  // the earlier lights' slots stay
  if (const uint64_t marked = mark(std::numeric_limits<float>::infinity()); marked > room) {
    const std::string over = "the view marks " + std::to_string(marked) +
                             " pages, more than the pool's " + std::to_string(room) + " free";
    if (sm.virtual_refuse_coarsening)
      throw ResourceExhausted("shadow_map.virtual_pool_pages",
                              over +
                                  ", and the request refuses coarser pages: raise "
                                  "virtual_pool_pages or virtual_lod_bias");
    double fits = std::log2(double(camera.near)), over_at = std::log2(double(camera.far));
    if (mark(float(std::exp2(fits))) > room)
      throw ResourceExhausted("shadow_map.virtual_pool_pages",
                              over +
                                  ", and even every pixel's level one coarser per doubling "
                                  "of its distance past the near plane does not fit: raise "
                                  "virtual_pool_pages or virtual_lod_bias");
    for (int i = 0; i < 12; ++i) {  // the coarsening distance to 2^(log2(far / near) / 4096)
      const double mid = 0.5 * (fits + over_at);
      (mark(float(std::exp2(mid))) > room ? over_at : fits) = mid;
    }
    mark(float(std::exp2(fits)));
    c.coarsened_pixels += virtual_pages.pixel_counts().coarsened;
  }
  invalidate_pages(s, *map);
  virtual_pages.allocate(s.light, *map, s.timeline);
  s.res.pages = map;
  const VirtualPagesPass::Counts counts = virtual_pages.counts();
  c.requested = counts.marked, c.resident = counts.held, c.rendered = counts.drawn;
}

void Workspace::invalidate_pages(StepContext& s, VirtualMap& map) {
  const VirtualLevels& layout = map.layout;
  const ShadowMapSettings& sm = s.one.shadow_map;
  const LightItem light = light_item(only_light(s.one));
  StepKey key;
  key.add(scene_->id()).bytes(&light, sizeof light).add(layout.texels).add(layout.view);
  key.add(layout.depth.near).add(layout.depth.far);
  for (const glm::dmat4& face : layout.face_ndc) key.add(face);
  key.add(sm.bias_world_constant).add(sm.bias_world_texel);
  const std::vector<InstanceBounds> now = instance_bounds(*s.one.scene, *scene_);
  bool all = !cache.keeping() || key.value() != map.drawn_from || now.size() != map.casters.size();
  std::vector<glm::vec4> boxes;
  // A moved caster's light-space box: across a directional light's view, or on a spot light's
  // map (mip 0's texture NDC). A point light's six faces are not sorted out: every page goes.
  const auto light_box = [&](const Bounds& world) -> std::optional<Bounds> {
    if (!layout.perspective()) return transform_bounds(world, layout.view);
    if (layout.faces != 1) return std::nullopt;
    Bounds b;
    for (const glm::dvec3& c : world.corners()) {
      const glm::dvec4 h = layout.face_ndc[0] * glm::dvec4(c, 1.0);
      if (!(h.w > 0)) return std::nullopt;  // reaches behind the light
      b.extend(glm::dvec3(h) / h.w);
    }
    return b;
  };
  for (size_t i = 0; i < now.size() && !all; ++i) {
    const InstanceBounds &was = map.casters[i], &is = now[i];
    if (was.casts == is.casts && was.world.lo == is.world.lo && was.world.hi == is.world.hi)
      continue;
    for (const InstanceBounds* b : {&was, &is})
      if (b->casts) {
        const std::optional<Bounds> ls = light_box(b->world);
        if (!ls)
          all = true;
        else
          boxes.emplace_back(ls->lo.x, ls->lo.y, ls->hi.x, ls->hi.y);
      }
  }
  virtual_pages.invalidate(s.light, all, boxes, layout.texels, s.timeline);
  map.drawn_from = key.value();
  map.casters = now;
}

void Workspace::run_render_maps(StepContext& s) {
  LightResources& res = s.res;
  if (res.pages) {
    DrawnMaps maps = fitter.draw_pages(s.one, *scene_, virtual_pages, *res.pages, s.timeline);
    res.maps = std::move(maps.maps);
    res.fit.report.raster_overlaps = maps.load.overlaps;
    res.fit.report.raster_box_pixels = maps.load.box_pixels;
    return;
  }
  res.map_from_probe = quality.take_map(s.one, s.light, s.plan, res);
  RasterLoad drawn;
  if (res.map_from_probe) {
    s.timeline.reuse(s.pass);
    drawn = res.single_map->load;
  } else {
    DrawnMaps maps = fitter.draw(s.one, *scene_, res.fit, true, s.plan.blur_planes, s.timeline);
    res.maps = std::move(maps.maps);
    res.single_map = maps.single;
    res.single_map_draws = maps.single_draws;
    drawn = maps.load;
  }
  res.fit.report.raster_overlaps = drawn.overlaps;
  res.fit.report.raster_box_pixels = drawn.box_pixels;
}

void Workspace::run_blur_planes(StepContext& s) {
  const uint32_t size = s.req.shadow_map.size;
  s.res.blurred = &blur.classify(*s.res.single_map, s.res.single_map_draws, size,
                                 s.plan.blur_planes, s.timeline);
  blur.blur(*s.res.blurred, size, size, s.plan.blur_planes, s.req.filter.blur.radius,
            s.req.filter.blur.passes, s.timeline);
}

void Workspace::run_visibility(StepContext& s) {  // a cube: each face decides the pixels it owns
  if (is_atlas_filter(s.one.filter.kind)) {
    const AtlasSoftenPass::AtlasInputs in{scene_.get(), &atlas.uvs(), &atlas.instance_tiles(),
                                          &atlas.soft(s.prefix), atlas.width()};
    s.res.visibility =
        &atlas_soften.lookup(*s.shared.view, s.pixels(), only_light(s.one), in, s.timeline);
    return;
  }
  if (s.res.map_from_probe && quality.hard_test() && taken_from_probe(s.req, s.plan, s.step.kind)) {
    s.res.visibility = quality.hard_test();  // the probe's test of this very map
    s.timeline.reuse(s.pass);
    return;
  }
  s.res.visibility = &visibility(s.one, s.plan, *s.shared.view, s.pixels(), s.req.camera.width,
                                 s.res, s.blocker_depth, s.timeline);
}

void Workspace::run_texel_density(StepContext& s) {
  s.res.density = &texel_density.run(*s.shared.view, s.req.camera, s.camera, s.res.maps,
                                     s.one.shadow_map.size, s.timeline);
}

uint64_t Workspace::source_key(const StepContext& s, Resource r) const {
  if (r == Resource::kAtlas) return s.res.atlas_key;
  if (r == Resource::kLightMaps)
    return StepKey{}.add(s.res.single_map, s.res.single_map->version).value();
  return 0;
}

// A prefilter of a kept result (the light's map or atlas) is kept with it: its slot is the
// pass's storage, which the lights share (their keys tell them apart). The camera's visibility
// is made anew every frame, and so are its prefilters.
void Workspace::run_mips(StepContext& s) {
  const Resource r = s.step.reads[0];
  const uint64_t source = source_key(s, r);
  const uint64_t key = StepKey{}.add(source).add(std::string("mips")).value();
  if (source && cache.take("mips:" + s.pass, key, s.pass, s.timeline)) {
    s.res.chains[s.step.writes[0]] = mips.last(s.pass);
    return;
  }
  s.res.chains[s.step.writes[0]] = &mips.run(this->source(s, r), s.pass, s.timeline);
  if (source) cache.made("mips:" + s.pass, key);
}

void Workspace::run_sat(StepContext& s) {  // the atlas' with its coverage: empty texels are not 0
  const Resource r = s.step.reads[0];
  const uint64_t source = source_key(s, r);
  const uint64_t key = StepKey{}.add(source).add(std::string("sat")).value();
  if (source && cache.take("sat:" + s.pass, key, s.pass, s.timeline)) {
    s.res.tables[s.step.writes[0]] = sat.last(s.pass);
    return;
  }
  const DeviceTexture src =
      r == Resource::kAtlas ? atlas.coverage(*s.res.atlas, s.timeline) : this->source(s, r);
  s.res.tables[s.step.writes[0]] = &sat.run(src, s.pass, s.timeline);
  if (source) cache.made("sat:" + s.pass, key);
}

void Workspace::run_csm_basis(StepContext& s) {
  LightResources& res = s.res;
  if (res.fit.cube) return;  // a basis per face, each before its face's lookups (face_basis)
  const CsmSettings& c = s.req.filter.csm;
  const MapDepth& depth = res.fit.light.depth;
  const uint64_t key = StepKey{}
                           .add(res.single_map, res.single_map->version)
                           .add(depth.kind)
                           .add(depth.near)
                           .add(depth.far)
                           .add(c.terms)
                           .add(c.storage)
                           .add(s.plan.csm_blocker)
                           .add(s.plan.csm_prefilter)
                           .value();
  if (cache.take("csm.basis", key, s.pass, s.timeline)) {
    res.csm_basis = &csm.basis();
    return;
  }
  res.csm_basis = &csm.build(res.single_map->depth, s.req.shadow_map.size, depth, c.terms,
                             c.storage == CsmStorage::kFloat16, s.plan.csm_blocker,
                             s.plan.csm_prefilter, s.timeline);
  cache.made("csm.basis", key);
}

void Workspace::run_atlas_view(StepContext& s) {
  s.shared.atlas_view = &atlas.bake(s.req, *scene_, s.timeline);
}

void Workspace::run_atlas_visibility(StepContext& s) {
  LightResources& res = s.res;
  // The bake, the light, its maps, the filter and the test's bias.
  StepKey key;
  key.add(atlas.bake_version()).add(only_light(s.one)).add(s.one.filter);
  key.add_test(s.one.shadow_map).add(s.req.atlas.gutter);
  for (const LightMap& m : res.maps) key.add(m.depth, m.version);
  res.atlas_key = key.value();
  const std::string slot = "atlas:" + s.prefix;
  if (cache.take(slot, res.atlas_key, s.pass, s.timeline)) {
    res.atlas = &atlas.result(s.prefix);
    return;
  }
  // The visibility passes' own names under "atlas."; the camera's blocker depth is not the
  // atlas' to write. The atlas filters prefilter the hard test.
  s.timeline.set_prefix(s.prefix + "atlas.");
  RenderRequest hard;
  const bool lookup = is_atlas_filter(s.one.filter.kind);
  if (lookup) hard = s.one, hard.filter.kind = FilterKind::kHard;
  const cl::Buffer* filtered =
      &visibility(lookup ? hard : s.one, s.plan, *s.shared.atlas_view,
                  atlas.width() * atlas.height(), atlas.width(), res, false, s.timeline);
  s.timeline.set_prefix(s.prefix);
  res.atlas = &atlas.finish(*filtered, s.req.atlas.gutter, s.prefix, s.timeline);
  cache.made(slot, res.atlas_key);
}

void Workspace::run_atlas_soften(StepContext& s) {  // made with this light's atlas, kept with it
  LightResources& res = s.res;
  // The light's atlas (its maps and filter among its inputs), and its prefilter.
  const Resource prefilter = s.step.reads.back();  // kAtlasSat or kAtlasMips
  const uint64_t key = StepKey{}.add(res.atlas_key).add(prefilter).value();
  const std::string slot = "atlas.soften:" + s.prefix;
  if (cache.take(slot, key, s.pass, s.timeline)) return;
  const LightMap& m = res.maps.at(0);  // uniform maps only
  const Light& light = only_light(s.one);
  pcss.penumbra(*s.shared.atlas_view, atlas.width() * atlas.height(), atlas.width(), *m.depth,
                m.setup, light, s.one.shadow_map, s.one.filter.pcss, atlas.penumbra(s.prefix),
                s.timeline);
  const bool sat_lookup = filter_facts(s.one.filter.kind).atlas == FilterFacts::Atlas::kSat;
  AtlasSoftenPass::AtlasPrefiltered in;
  in.half_width = &atlas.penumbra(s.prefix);
  in.sat = sat_lookup ? res.tables.at(Resource::kAtlasSat) : nullptr;
  in.level0 = res.atlas;
  in.mips = sat_lookup ? nullptr : res.chains.at(Resource::kAtlasMips);
  in.texel_axes = &atlas.texel_axes();
  in.texel_charts = &atlas.texel_charts();
  in.width = atlas.width(), in.height = atlas.height(), in.tile = atlas.tile();
  in.cells = &atlas.tile_cells(), in.cell = atlas.cell();
  atlas_soften.soften(*s.shared.atlas_view, m.setup, light, s.one.shadow_map, in,
                      atlas.soft(s.prefix), s.timeline);
  cache.made(slot, key);
}

void Workspace::run_readback(StepContext& s) {
  const auto source_of = [&](Resource r) { return source(s, r); };
  const bool last = s.light + 1 >= s.req.lights.size();
  for (Texture& t : readback.products(s.one, s.light, last, light_texture_suffix(s.req, s.light),
                                      s.camera, s.shared, s.res, *scene_, source_of, s.timeline)) {
    if (per_light(t.kind)) t.light = s.light;
    s.textures.push_back(std::move(t));
  }
}

}  // namespace shadow
