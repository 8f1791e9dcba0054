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
      virtual_pages(runtime, kernels),
      fitter(rasterizer, view_samples, light_distance, edge_sampling, empty_map),
      quality(gbuffer, view_samples, shadow_test, depth_range, boundary, rasterizer, fitter),
      readback(runtime, half_pack, csm, atlas, virtual_pages, empty_map) {
  runtime.ensure(empty_map, sizeof(float));
  rasterizer.set_cache(&cache);
  atlas.set_cache(&cache);
  fitter.set_cache(&cache);
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
  virtual_pages.warm_up();
}

RenderResult Workspace::render(const RenderRequest& request, const Plan& plan,
                               const RenderControl& control) {
  runtime.set_cancelled(control.cancelled);
  runtime.set_account(control.client, control.estimate_ms, control.guard_slack_ms);
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
    if (control.progress)
      runtime.set_progress([&](double ms) {
        control.progress(
            {timeline.passes().empty() ? "" : timeline.passes().back(), ms, control.estimate_ms});
      });
    RenderResult result;
    if (request.quality.goal == Quality::Goal::kNone) {
      result = run(request, plan, control, timeline);
    } else {
      if (!control.calibration || !control.candidate_cost)
        throw std::logic_error("a quality goal needs the engine's calibration and cost");
      // The pick uploads the scene; the run keeps it.
      upload_scene(request, control, cache.keeping(), "scene", timeline);
      scene_uploaded_ = true;
      QualityProbe::Picked picked =
          quality.pick(request, *scene_, *control.calibration, control.candidate_cost, timeline);
      result = run(picked.request, picked.plan, control, timeline);
      quality.forget();  // what the run did not take (a shadow map alone takes no camera view)
      result.quality = std::move(picked.quality);
    }
    runtime.set_cancelled({});
    runtime.set_progress({});
    fitter.frame_done();
    if (!sequence_) {
      if (cache.keeping()) {
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
    runtime.set_progress({});
    runtime.drain();
    quality.forget();
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
  cache.keep(keep);
  fitter.forget_trials();
  warm_.reset();
  scene_.reset();
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
    case Lookup::kPcss: {  // uniform maps only, or a virtual map's levels
      const LightMap& m = maps.at(0);
      return pcss.run(view, pixels, width, *m.depth, m.setup, light, req.shadow_map, f.pcss,
                      timeline, m.pages);
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
  cache.forget("csm.basis");  // the basis kept for a sequence is overwritten
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
  const ViewSetup camera = camera_setup(req.camera);
  // Each light's steps read the request narrowed to it (engine/plan/light_request.hpp); a request
  // with no light (POSITION alone) runs the camera's steps only.
  std::vector<RenderRequest> lights;
  for (size_t i = 0; i < req.lights.size(); ++i) lights.push_back(for_light(req, i));
  if (lights.empty()) lights.push_back(req);
  RenderResult result;
  result.light_fits.resize(req.lights.size());
  readback.set_format(req.output_format);

  StepLedger ledger;
  SharedResources shared_res;
  // The current light's: its steps run together, ending with its readback.
  LightResources res;
  std::vector<Texture> textures;
  const bool blocker_depth = std::find(req.products.begin(), req.products.end(),
                                       Product::kBlockerDepth) != req.products.end();
  for (const Step& step : plan.steps) {
    const uint32_t last = ledger.light();
    if (ledger.enter(step)) {
      result.light_fits.at(last) = res.fit.report;
      res = {};
    }
    const uint32_t current = ledger.light();
    const std::string prefix = is_shared(step.kind) ? "" : light_pass_prefix(req, current);
    timeline.set_prefix(prefix);
    StepContext s{req,
                  lights[current],
                  plan,
                  step,
                  current,
                  prefix,
                  step.name.substr(prefix.size()),  // the timeline adds the prefix
                  camera,
                  shared_res,
                  res,
                  control,
                  textures,
                  timeline,
                  blocker_depth};
    (this->*runner(step.kind))(s);
    ledger.done(step);
  }
  if (!req.lights.empty()) result.light_fits.at(ledger.light()) = res.fit.report;
  order_products(req, textures);
  result.textures = std::move(textures);
  runtime.finish();
  result.passes = timeline.passes();
  result.reused = timeline.reused();
  result.rerun = timeline.reran();
  result.virtual_pages = shared_res.virtual_pages;
  if (control.profile) result.timings = timeline.timings();
  return result;
}

}  // namespace shadow
