#include "engine/run/workspace.hpp"

#include <algorithm>
#include <atomic>
#include <map>
#include <optional>
#include <stdexcept>

#include "engine/passes/scene_buffers.hpp"
#include "engine/plan/atlas_layout.hpp"
#include "engine/plan/filter.hpp"
#include "engine/plan/light_request.hpp"
#include "engine/plan/plan.hpp"
#include "engine/plan/sequence.hpp"
#include "wire/errors.hpp"

namespace shadow {

Workspace::Workspace(std::shared_ptr<const cl::Device> device, cl::ProgramCache& programs)
    : runtime(std::move(device)),
      kernels(programs),
      rasterizer(runtime, kernels),
      gbuffer(runtime, kernels, rasterizer),
      shadow_test(runtime, kernels),
      texel_density(runtime, kernels),
      pcf(runtime, kernels),
      pcss(runtime, kernels),
      atlas_soften(runtime, kernels),
      mips(runtime, kernels),
      sat(runtime, kernels),
      csm(runtime, kernels, mips, sat),
      blur(runtime, kernels),
      light_distance(runtime, kernels),
      depth_range(runtime, kernels),
      boundary(runtime, kernels),
      edge_sampling(runtime, kernels),
      view_samples(runtime, kernels),
      half_pack(runtime, kernels),
      atlas(runtime, kernels),
      fitter(rasterizer, view_samples, light_distance, edge_sampling, empty_map),
      quality(gbuffer, view_samples, shadow_test, depth_range, boundary, rasterizer, fitter),
      readback(runtime, half_pack, csm, atlas, empty_map) {
  runtime.ensure(empty_map, sizeof(float));
}

void Workspace::create_kernels() {
  rasterizer.warm_up();
  gbuffer.warm_up();
  shadow_test.warm_up();
  texel_density.warm_up();
  pcf.warm_up();
  pcss.warm_up();
  atlas_soften.warm_up();
  mips.warm_up();
  sat.warm_up();
  csm.warm_up();
  blur.warm_up();
  light_distance.warm_up();
  depth_range.warm_up();
  boundary.warm_up();
  edge_sampling.warm_up();
  view_samples.warm_up();
  half_pack.warm_up();
  atlas.warm_up();
}

RenderResult Workspace::render(const RenderRequest& request, const Plan& plan,
                               const RenderControl& control) {
  runtime.set_cancelled(control.cancelled);
  runtime.set_account(control.client, control.estimate_ms);
  rasterizer.set_max_cost_ms(control.max_cost_ms);
  fitter.set_calibration(control.calibration);
  if (!sequence_) {
    // A request that continues the last one on a scene still held takes its results as a
    // sequence's frame would; any other starts afresh, keeping its own if its scene is held.
    const bool warm = warm_ && request.scene_held && warm_->scene.lock() == request.scene &&
                      same_settings(warm_->settings, request) && control.resident &&
                      control.resident->held(request.scene) == warm_->buffers.lock();
    if (!warm)
      start_keeping(request.scene_held && request.quality.goal == Quality::Goal::kNone &&
                    control.resident);
    warm_.reset();
  }
  try {
    Timeline timeline;
    RenderResult result;
    if (request.quality.goal == Quality::Goal::kNone) {
      result = run(request, plan, control, timeline);
    } else {
      if (!control.calibration || !control.candidate_cost)
        throw std::logic_error("a quality goal needs the engine's calibration and cost");
      // The pick uploads the scene; the run keeps it.
      upload_scene(request, control, keeping_, "scene", timeline);
      scene_uploaded_ = true;
      QualityProbe::Picked picked =
          quality.pick(request, *scene_, *control.calibration, control.candidate_cost, timeline);
      result = run(picked.request, picked.plan, control, timeline);
      quality.forget();  // what the run did not take (a shadow map alone takes no camera view)
      result.quality = std::move(picked.quality);
    }
    runtime.set_cancelled({});
    fitter.frame_done();
    if (!sequence_) {
      if (keeping_) {
        warm_ = Warm{request.scene, request, scene_};
        warm_->settings.scene.reset();
        warm_->settings.lights.clear();
      }
      scene_.reset();  // the resident scenes hold it while it is kept
    }
    return result;
  } catch (...) {
    // Asynchronous writes may still read the request's memory: drain before it goes (the
    // runtime drained already if it threw; host code between its calls may have thrown too).
    runtime.set_cancelled({});
    runtime.drain();
    quality.forget();
    csm_made_from_.reset();
    scene_uploaded_ = false;
    if (!sequence_) start_keeping(false);
    throw;
  }
}

void Workspace::make_resident(const std::shared_ptr<const Scene>& scene, ResidentScenes& resident,
                              std::function<bool()> cancelled, const std::string& client) {
  runtime.set_cancelled(std::move(cancelled));
  runtime.set_account(client);
  try {
    Timeline timeline;
    bool held = false;
    resident.get(
        scene,
        [&] { return std::make_shared<const SceneBuffers>(runtime, kernels, *scene, timeline); },
        held);
  } catch (...) {
    runtime.set_cancelled({});
    runtime.drain();
    throw;
  }
  runtime.set_cancelled({});
}

void Workspace::start_keeping(bool keep) {
  keeping_ = keep;
  fitter.start_keeping(keep);
  warm_.reset();
  scene_.reset();
  rasterizer.set_reuse(keep);  // each forgets its last results
  atlas.set_reuse(keep);
  csm_made_from_.reset();
}

uint64_t Workspace::begin_sequence() {
  static std::atomic<uint64_t> last_id{0};
  start_keeping(true);
  sequence_ = ++last_id;
  return sequence_;
}

void Workspace::end_sequence() {
  sequence_ = 0;
  start_keeping(false);
}

const Scene* Workspace::warm_scene() const {
  return warm_ ? warm_->scene.lock().get() : nullptr;
}

bool Workspace::CsmInputs::operator==(const CsmInputs& o) const {
  const CsmSettings &a = settings, &b = o.settings;
  return map == o.map && version == o.version && depth == o.depth && a.terms == b.terms &&
         a.storage == b.storage && blocker == o.blocker && prefilter == o.prefilter;
}

const cl::Buffer& Workspace::visibility(const RenderRequest& req, const Plan& plan,
                                        const GBuffer& view, uint32_t pixels, uint32_t width,
                                        LightResources& res, bool blocker_depth,
                                        Timeline& timeline) {
  const std::vector<LightMap>& maps = res.maps;
  const Filter& f = req.filter;
  const Light& light = only_light(req);
  using Lookup = FilterFacts::Lookup;
  switch (filter_facts(f.kind).lookup) {
    case Lookup::kShadowTest:
      return shadow_test.run(view, pixels, maps, light, req.shadow_map, timeline);
    case Lookup::kPcfBilinear:
      return pcf.run(view, pixels, width, maps, light, req.shadow_map, PcfParams{}, timeline);
    case Lookup::kPcfPoisson: {
      const PcfParams params{PcfParams::Mode::kPoisson, f.poisson.taps, f.poisson.radius,
                             f.poisson.rotate};
      return pcf.run(view, pixels, width, maps, light, req.shadow_map, params, timeline);
    }
    case Lookup::kPcss: {  // uniform maps only
      const LightMap& m = maps.at(0);
      return pcss.run(view, pixels, width, *m.depth, m.setup, light, req.shadow_map, f.pcss,
                      timeline);
    }
    case Lookup::kBlur: {  // uniform maps only
      // Class receivers read their blurred plane; everything else keeps the hard test.
      const cl::Buffer& vis = shadow_test.run(view, pixels, maps, light, req.shadow_map, timeline);
      if (res.blurred)
        blur.apply(view, pixels, *res.blurred, maps.at(0).setup, light, req.shadow_map.size, vis,
                   timeline);
      return vis;
    }
    case Lookup::kAtlas:
      throw std::logic_error("the atlas filters read the atlas' prefiltered tables (run)");
    case Lookup::kCsm: {
      const cl::Buffer* vis = nullptr;
      for (const LightMap& m : maps) {  // a single map's basis is the kCsmBasis step's
        if (is_cube(maps)) res.csm_basis = &face_basis(req, plan, m, timeline);
        vis = &csm.visibility(view, pixels, *res.csm_basis, m.setup, light, req.shadow_map, f,
                              blocker_depth, timeline);
      }
      return *vis;
    }
  }
  throw std::logic_error("unknown filter kind");
}

const CsmBasis& Workspace::face_basis(const RenderRequest& req, const Plan& plan,
                                      const LightMap& map, Timeline& timeline) {
  csm_made_from_.reset();  // the basis kept for a sequence is overwritten
  const CsmSettings& c = req.filter.csm;
  // The faces not rendered share a one-texel empty map, which their lookups never read (every
  // pixel is off it).
  const uint32_t size = fitter.rendered(map) ? req.shadow_map.size : 1;
  return csm.build(*map.depth, size, map.setup.depth, c.terms, c.storage == CsmStorage::kFloat16,
                   plan.csm_blocker, plan.csm_prefilter, timeline);
}

void Workspace::upload_scene(const RenderRequest& req, const RenderControl& control, bool reuse,
                             const std::string& pass, Timeline& timeline) {
  const auto upload = [&] {
    return std::make_shared<const SceneBuffers>(runtime, kernels, *req.scene, timeline);
  };
  bool held = reuse && scene_;
  if (!held)
    scene_ = req.scene_held && control.resident ? control.resident->get(req.scene, upload, held)
                                                : upload();
  if (held) timeline.reuse(pass);
}

RenderResult Workspace::run(const RenderRequest& req, const Plan& plan,
                            const RenderControl& control, Timeline& timeline) {
  const Scene& scene = *req.scene;
  const ViewSetup camera = camera_setup(req.camera);
  const uint32_t pixels = req.camera.width * req.camera.height;
  // Each light's steps read the request narrowed to it (engine/plan/light_request.hpp); a request
  // with no light (POSITION alone) runs the camera's steps only.
  std::vector<RenderRequest> lights;
  for (size_t i = 0; i < req.lights.size(); ++i) lights.push_back(for_light(req, i));
  if (lights.empty()) lights.push_back(req);
  const std::shared_ptr<const SceneBuffers>& buffers = scene_;
  RenderResult result;
  result.light_fits.resize(req.lights.size());

  StepLedger ledger;
  SharedResources shared_res;
  // The current light's: its steps run together, ending with its readback.
  LightResources res;
  readback.set_format(req.output_format);
  const bool blocker_depth = std::find(req.products.begin(), req.products.end(),
                                       Product::kBlockerDepth) != req.products.end();
  const uint32_t size = req.shadow_map.size;
  const auto source = [&](Resource r) {  // the texture a mip chain or SAT filters
    switch (r) {
      case Resource::kLightMaps:
        return DeviceTexture{&res.single_map->depth, size, size, 1};
      case Resource::kAtlas:
        return DeviceTexture{res.atlas, atlas.width(), atlas.height(), 1};
      default:
        return DeviceTexture{res.visibility, req.camera.width, req.camera.height, 1};
    }
  };

  std::vector<Texture> textures;
  for (const Step& step : plan.steps) {
    const uint32_t last = ledger.light();
    if (ledger.enter(step)) {
      result.light_fits.at(last) = res.fit.report;
      res = {};
    }
    const uint32_t current = ledger.light();
    const bool shared = is_shared(step.kind);
    const RenderRequest& one = lights[current];
    const std::string prefix = shared ? "" : light_pass_prefix(req, current);
    timeline.set_prefix(prefix);
    const std::string pass = step.name.substr(prefix.size());  // the timeline adds the prefix
    switch (step.kind) {
      case StepKind::kUploadScene:
        if (scene_uploaded_)  // by the quality pick, in this timeline
          scene_uploaded_ = false;
        else
          upload_scene(req, control, keeping_, pass, timeline);
        break;
      case StepKind::kCameraView: {
        const GBuffer* probed = quality.take_view();
        shared_res.view =
            probed ? probed : &gbuffer.run(scene, *buffers, req.camera, camera, timeline);
        break;
      }
      case StepKind::kDepthRange:
        if (std::optional<std::optional<DepthRange>> probed = quality.take_depth()) {
          shared_res.measured = *probed;  // the probe measured this very view
          timeline.reuse(pass);
        } else {
          shared_res.measured = depth_range.run(*shared_res.view, req.camera, timeline);
        }
        break;
      case StepKind::kFitLight:
        res.fit =
            fitter.fit(one, current, *buffers, shared_res.measured, shared_res.view, timeline);
        lights[current].shadow_map.size = res.fit.map_size;  // AUTO's PSM cube: its faces'
        // Unrendered: texel density reads their matrices only.
        res.maps = fitter.draw(one, *buffers, res.fit, false, 0, timeline).maps;
        break;
      case StepKind::kRenderMaps: {
        res.map_from_probe = quality.take_map(one, current, plan, res);
        RasterLoad drawn;
        if (res.map_from_probe) {
          timeline.reuse(pass);
          drawn = res.single_map->load;
        } else {
          DrawnMaps maps = fitter.draw(one, *buffers, res.fit, true, plan.blur_planes, timeline);
          res.maps = std::move(maps.maps);
          res.single_map = maps.single;
          res.single_map_draws = maps.single_draws;
          drawn = maps.load;
        }
        res.fit.report.raster_overlaps = drawn.overlaps;
        res.fit.report.raster_box_pixels = drawn.box_pixels;
        break;
      }
      case StepKind::kBlurPlanes:
        res.blurred =
            &blur.classify(*res.single_map, res.single_map_draws, size, plan.blur_planes, timeline);
        blur.blur(*res.blurred, size, size, plan.blur_planes, req.filter.blur.radius,
                  req.filter.blur.passes, timeline);
        break;
      case StepKind::kVisibility:  // a cube: each face decides the pixels it owns
        if (is_atlas_filter(one.filter.kind)) {
          const AtlasSoftenPass::AtlasInputs in{buffers.get(), &atlas.uvs(),
                                                &atlas.instance_tiles(), &atlas.soft(prefix),
                                                atlas.width()};
          res.visibility =
              &atlas_soften.lookup(*shared_res.view, pixels, only_light(one), in, timeline);
          break;
        }
        if (res.map_from_probe && quality.hard_test() && taken_from_probe(req, plan, step.kind)) {
          res.visibility = quality.hard_test();  // the probe's test of this very map
          timeline.reuse(pass);
          break;
        }
        res.visibility = &visibility(one, plan, *shared_res.view, pixels, req.camera.width, res,
                                     blocker_depth, timeline);
        break;
      case StepKind::kAtlasView:
        shared_res.atlas_view = &atlas.bake(req, *buffers, timeline);
        break;
      case StepKind::kAtlasVisibility: {
        // In a sequence the filter and settings are the same every frame: the light and its
        // maps decide the rest.
        AtlasPass::Inputs inputs{only_light(one), {}};
        for (const LightMap& m : res.maps) inputs.maps.emplace_back(m.depth, m.version);
        if (const cl::Buffer* kept = atlas.kept(prefix, inputs)) {
          timeline.reuse(pass);
          res.atlas = kept;
          res.atlas_kept = true;
          break;
        }
        // The visibility passes' own names under "atlas."; the camera's blocker depth is not
        // the atlas' to write.
        timeline.set_prefix(prefix + "atlas.");
        // The atlas filters prefilter the hard test.
        RenderRequest hard;
        const bool lookup = is_atlas_filter(one.filter.kind);
        if (lookup) hard = one, hard.filter.kind = FilterKind::kHard;
        const cl::Buffer* filtered =
            &visibility(lookup ? hard : one, plan, *shared_res.atlas_view,
                        atlas.width() * atlas.height(), atlas.width(), res, false, timeline);
        timeline.set_prefix(prefix);
        res.atlas = &atlas.finish(*filtered, req.atlas.gutter, prefix, inputs, timeline);
        break;
      }
      case StepKind::kAtlasSoften: {  // made with this light's atlas, so kept with it
        if (res.atlas_kept) {
          timeline.reuse(pass);
          break;
        }
        const LightMap& m = res.maps.at(0);  // uniform maps only
        const uint32_t texels = atlas.width() * atlas.height();
        pcss.penumbra(*shared_res.atlas_view, texels, atlas.width(), *m.depth, m.setup,
                      only_light(one), one.shadow_map, one.filter.pcss, atlas.penumbra(prefix),
                      timeline);
        const bool sat_lookup = filter_facts(one.filter.kind).atlas == FilterFacts::Atlas::kSat;
        AtlasSoftenPass::AtlasPrefiltered in;
        in.half_width = &atlas.penumbra(prefix);
        in.sat = sat_lookup ? res.tables.at(Resource::kAtlasSat) : nullptr;
        in.level0 = res.atlas;
        in.mips = sat_lookup ? nullptr : res.chains.at(Resource::kAtlasMips);
        in.texel_axes = &atlas.texel_axes();
        in.texel_charts = &atlas.texel_charts();
        in.width = atlas.width(), in.height = atlas.height(), in.tile = atlas.tile();
        in.cells = &atlas.tile_cells(), in.cell = atlas.cell();
        atlas_soften.soften(*shared_res.atlas_view, m.setup, only_light(one), one.shadow_map, in,
                            atlas.soft(prefix), timeline);
        break;
      }
      case StepKind::kTexelDensity:
        res.density = &texel_density.run(*shared_res.view, req.camera, camera, res.maps,
                                         one.shadow_map.size, timeline);
        break;
      case StepKind::kMips:
        if (const MipChain* kept =
                kept_atlas_prefilter(step, prefix, res) ? mips.last(pass) : nullptr) {
          timeline.reuse(pass);
          res.chains[step.writes[0]] = kept;
          break;
        }
        res.chains[step.writes[0]] = &mips.run(source(step.reads[0]), pass, timeline);
        break;
      case StepKind::kSat: {  // the atlas' with its coverage: its empty texels are not zeros
        const Resource r = step.reads[0];
        if (const SummedAreaTable* kept =
                kept_atlas_prefilter(step, prefix, res) ? sat.last(pass) : nullptr) {
          timeline.reuse(pass);
          res.tables[step.writes[0]] = kept;
          break;
        }
        const DeviceTexture src =
            r == Resource::kAtlas ? atlas.coverage(*res.atlas, timeline) : source(r);
        res.tables[step.writes[0]] = &sat.run(src, pass, timeline);
        break;
      }
      case StepKind::kCsmBasis: {
        if (res.fit.cube) break;  // a basis per face, each before its face's lookups (face_basis)
        const CsmSettings& c = req.filter.csm;
        const CsmInputs inputs{res.single_map,   res.single_map->version, res.fit.light.depth, c,
                               plan.csm_blocker, plan.csm_prefilter};
        if (keeping_ && csm_made_from_ == inputs) {
          timeline.reuse(pass);
          res.csm_basis = &csm.basis();
          break;
        }
        csm_made_from_.reset();
        res.csm_basis = &csm.build(res.single_map->depth, size, inputs.depth, c.terms,
                                   c.storage == CsmStorage::kFloat16, plan.csm_blocker,
                                   plan.csm_prefilter, timeline);
        if (keeping_) csm_made_from_ = inputs;
        break;
      }
      case StepKind::kReadback:
        for (Texture& t : readback.products(one, current == 0, light_texture_suffix(req, current),
                                            camera, shared_res, res, *buffers, source, timeline)) {
          if (per_light(t.kind)) t.light = current;
          textures.push_back(std::move(t));
        }
        break;
    }
    ledger.done(step);
  }
  if (!req.lights.empty()) result.light_fits.at(ledger.light()) = res.fit.report;
  order_products(req, textures);
  result.textures = std::move(textures);
  runtime.finish();
  result.passes = timeline.passes();
  result.reused = timeline.reused();
  if (control.profile) result.timings = timeline.timings();
  return result;
}

}  // namespace shadow
