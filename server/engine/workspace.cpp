#include "engine/workspace.hpp"

#include <atomic>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>

#include "engine/atlas_layout.hpp"
#include "engine/auto_pick.hpp"
#include "engine/light_request.hpp"
#include "engine/light_space.hpp"
#include "engine/lispsm_fit.hpp"
#include "engine/plan.hpp"
#include "engine/psm_fit.hpp"
#include "engine/scene_buffers.hpp"
#include "engine/sequence.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

std::vector<InstanceBounds> instance_bounds(const Scene& scene, const SceneBuffers& buffers) {
  std::vector<InstanceBounds> out;
  for (const Instance& inst : scene.instances) {
    out.push_back({transform_bounds(buffers.meshes()[inst.mesh].bounds, glm::dmat4(inst.transform)),
                   inst.casts_shadows, inst.receives_shadows});
  }
  return out;
}

// Whether the instance's box reaches into the frustum of `world_to_ndc`.
bool reaches_into(const SceneBuffers& buffers, const Instance& i, const glm::dmat4& world_to_ndc) {
  return may_be_visible(transform_bounds(buffers.meshes()[i.mesh].bounds, glm::dmat4(i.transform)),
                        world_to_ndc);
}

// The world-space caster bias (Kozlov 14.3.1) of one light map; the camera view has none.
WorldBias world_bias(const RenderRequest& req, const ViewSetup& light) {
  WorldBias bias;
  bias.world_to_ndc = glm::mat4(light.world_to_ndc);
  bias.light = light_item(only_light(req));
  bias.constant = req.shadow_map.bias_world_constant;
  bias.texel = req.shadow_map.bias_world_texel;
  bias.map_size = req.shadow_map.size;
  return bias;
}

}  // namespace

Workspace::Workspace(std::shared_ptr<const cl::Device> device, cl::ProgramCache& programs)
    : runtime(std::move(device)),
      kernels(programs),
      rasterizer(runtime, kernels),
      gbuffer(runtime, kernels, rasterizer),
      shadow_test(runtime, kernels),
      texel_density(runtime, kernels),
      pcf(runtime, kernels),
      pcss(runtime, kernels),
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
      atlas(runtime, kernels) {
  runtime.ensure(empty_map, sizeof(float));
}

void Workspace::create_kernels() {
  rasterizer.warm_up();
  gbuffer.warm_up();
  shadow_test.warm_up();
  texel_density.warm_up();
  pcf.warm_up();
  pcss.warm_up();
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
  rasterizer.set_max_cost_ms(control.max_cost_ms);
  calibration_ = control.calibration;
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
      const QualityPick chosen = pick(request, control, timeline);
      const RenderRequest picked = with_pick(request, chosen);
      result = run(picked, make_plan(picked), control, timeline);
      forget_probe();  // what the run did not take (a shadow map alone takes no camera view)
      result.quality = chosen;
    }
    runtime.set_cancelled({});
    ++frame_;
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
    forget_probe();
    blurred = nullptr;
    csm_basis = nullptr;
    csm_made_from_.reset();
    scene_uploaded_ = false;
    if (!sequence_) start_keeping(false);
    throw;
  }
}

void Workspace::make_resident(const std::shared_ptr<const Scene>& scene, ResidentScenes& resident,
                              std::function<bool()> cancelled) {
  runtime.set_cancelled(std::move(cancelled));
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
  frame_ = 0;
  verdicts_.clear();
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

void Workspace::read_floats(const cl::Buffer& src, size_t first, size_t count, Texture& t,
                            size_t at, Timeline& timeline) {
  if (t.format == PixelFormat::kFloat16) {
    const cl::Buffer& packed = half_pack.run(src, uint32_t(first), uint32_t(count), timeline);
    timeline.add("readback", runtime.read(packed, t.data16.data() + at, count * sizeof(uint16_t)));
  } else {
    timeline.add("readback", runtime.read(src, t.data.data() + at, count * sizeof(float),
                                          first * sizeof(float)));
  }
}

Texture Workspace::float_texture(std::string name, Product kind, uint32_t w, uint32_t h,
                                 uint32_t channels, uint32_t faces) const {
  Texture t;
  t.name = std::move(name);
  t.kind = kind;
  t.width = w;
  t.height = h;
  t.channels = channels;
  t.format = half_ ? PixelFormat::kFloat16 : PixelFormat::kFloat32;
  const size_t n = size_t{w} * h * channels * faces;
  half_ ? t.data16.resize(n) : t.data.resize(n);
  return t;
}

Texture Workspace::read_texture(const cl::Buffer& buffer, std::string name, Product kind,
                                uint32_t w, uint32_t h, uint32_t channels, Timeline& timeline) {
  Texture t = float_texture(std::move(name), kind, w, h, channels);
  read_floats(buffer, 0, size_t{w} * h * channels, t, 0, timeline);
  return t;
}

const cl::Buffer& Workspace::visibility(const RenderRequest& req, const Plan& plan,
                                        const GBuffer& view, uint32_t pixels, uint32_t width,
                                        const std::vector<LightMap>& maps, Timeline& timeline) {
  const Filter& f = req.filter;
  const Light& light = only_light(req);
  switch (f.kind) {
    case FilterKind::kHard:
      return shadow_test.run(view, pixels, maps, light, req.shadow_map, timeline);
    case FilterKind::kPcf2x2:
      return pcf.run(view, pixels, width, maps, light, req.shadow_map, PcfParams{}, timeline);
    case FilterKind::kPoisson: {
      const PcfParams params{PcfParams::Mode::kPoisson, f.poisson.taps, f.poisson.radius,
                             f.poisson.rotate};
      return pcf.run(view, pixels, width, maps, light, req.shadow_map, params, timeline);
    }
    case FilterKind::kPcss: {  // uniform maps only
      const LightMap& m = maps.at(0);
      return pcss.run(view, pixels, width, *m.depth, m.setup, light, req.shadow_map, f.pcss,
                      timeline);
    }
    case FilterKind::kBlur: {  // uniform maps only
      // Class receivers read their blurred plane; everything else keeps the hard test.
      const cl::Buffer& vis = shadow_test.run(view, pixels, maps, light, req.shadow_map, timeline);
      if (blurred)
        blur.apply(view, pixels, *blurred, maps.at(0).setup, light, req.shadow_map.size, vis,
                   timeline);
      return vis;
    }
    case FilterKind::kAtlasSat:
    case FilterKind::kAtlasMip:
      throw std::logic_error("the atlas filters read the atlas' prefiltered tables (run)");
    case FilterKind::kCsm:
    case FilterKind::kPcssCsm: {
      const cl::Buffer* vis = nullptr;
      for (const LightMap& m : maps) {  // a single map's basis is the kCsmBasis step's
        if (is_cube(maps)) csm_basis = &face_basis(req, plan, m, timeline);
        vis = &csm.visibility(view, pixels, *csm_basis, m.setup, light, req.shadow_map, f,
                              csm_blocker_depth, timeline);
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
  const uint32_t size = map.depth == &empty_map ? 1 : req.shadow_map.size;
  return csm.build(*map.depth, size, map.setup.depth, c.terms, c.storage == CsmStorage::kFloat16,
                   plan.csm_blocker, plan.csm_prefilter, timeline);
}

std::vector<Texture> Workspace::read_mips(const DeviceTexture& src, const MipChain& chain,
                                          const std::string& name, Product kind,
                                          Timeline& timeline) {
  std::vector<Texture> out;
  out.push_back(read_texture(*src.buffer, name + "_mip0", kind, src.width, src.height, src.channels,
                             timeline));
  for (size_t i = 0; i < chain.levels.size(); ++i) {
    const MipLevel& l = chain.levels[i];
    Texture t = float_texture(name + "_mip" + std::to_string(i + 1), kind, l.width, l.height,
                              chain.channels);
    read_floats(chain.storage, l.offset, size_t{l.width} * l.height * chain.channels, t, 0,
                timeline);
    out.push_back(std::move(t));
  }
  return out;
}

Texture Workspace::read_sat(const SummedAreaTable& table, const std::string& name, Product kind,
                            Timeline& timeline) {
  Texture t;
  t.name = name + "_sat";
  t.kind = kind;
  t.width = table.width;
  t.height = table.height;
  t.channels = table.channels;
  t.format = PixelFormat::kFloat64;
  t.data64.resize(size_t{table.width} * table.height * table.channels);
  timeline.add("readback", runtime.read(table.sums, t.data64.data(), t.byte_size()));
  return t;
}

double Workspace::nearest_caster(const RenderRequest& req, const SceneBuffers& buffers,
                                 Timeline& timeline) {
  const std::vector<DrawItem> casters = make_draws(
      *req.scene, buffers, glm::mat4(1.0f), [](const Instance& i) { return i.casts_shadows; });
  return light_distance.run(buffers, casters, only_light(req).position, timeline);
}

std::array<CubeFaceFit, 6> Workspace::fit_point_cube(const RenderRequest& req,
                                                     const SceneBuffers& buffers,
                                                     const std::vector<InstanceBounds>& bounds,
                                                     Timeline& timeline,
                                                     std::optional<double> distance) {
  if (!distance) distance = nearest_caster(req, buffers, timeline);
  return fit_cube(only_light(req), req.camera, bounds, req.shadow_map.size,
                  filter_reach(req.filter), *distance, req.shadow_map.fit)
      .faces;
}

Texture Workspace::read_cube(const std::vector<LightMap>& maps, uint32_t size, std::string name,
                             Timeline& timeline) {
  const auto rendered = std::count_if(maps.begin(), maps.end(),
                                      [&](const LightMap& m) { return m.depth != &empty_map; });
  Texture t =
      float_texture(std::move(name), Product::kShadowMap, size, size, 1, uint32_t(rendered));
  const size_t face_floats = size_t{size} * size;
  for (const LightMap& m : maps) {
    if (m.depth == &empty_map) continue;  // the faces not rendered
    int k = 0;
    while (!(m.setup.faces.owned & (1u << k))) ++k;
    read_floats(*m.depth, 0, face_floats, t, t.cube_faces.size() * face_floats, timeline);
    t.cube_faces.push_back(
        {kCubeFaceNames[k], glm::mat4(m.setup.world_to_ndc), glm::mat4(m.setup.view)});
  }
  t.faces = uint32_t(t.cube_faces.size());
  return t;
}

Workspace::LightPlan Workspace::fit_light(const RenderRequest& req, uint32_t light_index,
                                          const SceneBuffers& buffers,
                                          const std::optional<DepthRange>& measured,
                                          const GBuffer* view, Timeline& timeline) {
  LightPlan plan;
  LightFitReport& report = plan.report;
  const std::vector<InstanceBounds> bounds = instance_bounds(*req.scene, buffers);
  Technique technique = req.shadow_map.technique;
  plan.map_size = req.shadow_map.size;
  std::string auto_reason;
  std::vector<AutoCandidateReport> auto_candidates;
  if (technique == Technique::kAuto) {
    std::optional<std::vector<Sample>> samples;
    if (view) samples = view_samples.run(*view, req.camera.width, req.camera.height, timeline);
    AutoPick pick = pick_technique(
        only_light(req), req.camera, bounds, req.shadow_map.size, req.filter.kind, measured,
        calibration_, samples ? &*samples : nullptr,
        auto_may_cube(req) ? std::optional<uint32_t>(filter_reach(req.filter)) : std::nullopt);
    if (view) try_candidates(req, light_index, buffers, measured, *view, pick, timeline);
    technique = pick.technique;
    plan.map_size = pick.size;
    auto_reason = pick.reason;
    for (const AutoCandidate& c : pick.candidates)
      auto_candidates.push_back({c.technique, c.size, uint32_t(c.faces), c.predicted_error,
                                 c.mean_footprint, c.trial_size, c.trial_edge});
  }
  if (technique == Technique::kCube) {
    plan.cube = true;
    plan.faces = fit_point_cube(req, buffers, bounds, timeline);
    report.light_case = "cube: point light";
  } else if (technique == Technique::kLispsm) {
    const LispsmFit fit =
        fit_lispsm_light(only_light(req), req.camera, bounds, req.shadow_map.lispsm, measured);
    plan.light = fit.setup;
    report.light_case = fit.light_case;
    report.lispsm_n = fit.n;
  } else if (technique == Technique::kUniform) {
    plan.light = fit_uniform_light(only_light(req), req.camera, bounds, req.shadow_map.fit);
    plan.cull = true;
    report.light_case =
        only_light(req).type == LightType::kSpot ? "uniform: spot" : "uniform: directional";
  } else {
    // Where a caster's box holds the light (a lamp in a room that is one mesh), the light's
    // nearest caster bounds PSM's near planes (psm_fit.hpp); measured only then.
    const Light& light = only_light(req);
    std::optional<double> distance;
    if (caster_box_holds_light(light, bounds)) distance = nearest_caster(req, buffers, timeline);
    PsmCubeFit pc;
    if (technique == Technique::kPsmCube)
      pc = fit_psm_cube(light, req.camera, bounds, req.shadow_map.psm, measured, plan.map_size,
                        filter_reach(req.filter), distance);
    else
      pc.fit = fit_psm_light(light, req.camera, bounds, req.shadow_map.psm, measured, distance);
    const PsmFit& fit = pc.fit;
    report = LightFitReport{};
    report.light_case = fit.light_case;
    report.virtual_near = fit.virtual_near, report.virtual_far = fit.virtual_far;
    report.slide_back = fit.slide_back;
    report.light_near = fit.light_near, report.light_far = fit.light_far;
    if (pc.cube) {
      plan.cube = true;
      plan.faces = pc.faces;
      report.cube_texel_min = pc.texel_min, report.cube_texel_max = pc.texel_max;
    } else if (fit.needs_cube && only_light(req).type == LightType::kPoint) {
      // A point light inside the view (or with no visible receiver): no single frustum sees it
      // all (a spot light's fit falls back to its uniform map itself).
      plan.cube = true;
      plan.faces = fit_point_cube(req, buffers, bounds, timeline, distance);
      report.light_case = fit.light_case + ": cube: point light";
    } else {
      plan.light = fit.setup;
    }
  }
  if (req.shadow_map.technique == Technique::kAuto) {
    report.auto_technique = technique;
    report.auto_reason = auto_reason;
    report.auto_map_size = plan.map_size;
    report.auto_candidates = std::move(auto_candidates);
    report.light_case = "auto: " + auto_reason + "; " + report.light_case;
  }
  if (plan.cube)
    for (int k = 0; k < 6; ++k)
      report.cube_faces.push_back(
          {kCubeFaceNames[k], plan.faces[k].rendered, plan.faces[k].reason});
  return plan;
}

void Workspace::try_candidates(const RenderRequest& req, uint32_t light,
                               const SceneBuffers& buffers,
                               const std::optional<DepthRange>& measured, const GBuffer& view,
                               AutoPick& pick, Timeline& timeline) {
  const std::vector<size_t> tried = trial_candidates(pick);
  if (tried.empty()) return;
  const auto last = keeping_ ? verdicts_.find(light) : verdicts_.end();
  if (last != verdicts_.end() && verdict_holds(pick, tried, last->second, frame_)) {
    std::vector<double> edge;
    std::vector<uint32_t> sizes;
    for (const AutoCandidate& c : last->second.tried)
      edge.push_back(c.trial_edge), sizes.push_back(c.trial_size);
    choose_by_trial(pick, tried, edge, sizes, last->second.picked, last->second.frame);
    return;
  }
  // Its own raster buffers ("[lightN.]light_fit.trial.shadow_map"), so a sequence keeps the
  // request's map; its tests write EdgeSamplingPass's own buffer.
  const std::string outer = timeline.scoped("");
  timeline.set_prefix(outer + "light_fit.trial.");
  const uint32_t width = req.camera.width, height = req.camera.height;
  std::vector<double> edge;
  std::vector<uint32_t> sizes;
  for (size_t i : tried) {
    const AutoCandidate& c = pick.candidates[i];
    RenderRequest trial = req;
    trial.shadow_map.technique = c.technique;
    trial.shadow_map.size = trial_size(c.size);
    // A cube's guard band must fit its faces (cube_fit.hpp); else the trial draws them whole.
    if (c.technique == Technique::kPsmCube &&
        filter_reach(req.filter) > max_guard(trial.shadow_map.size))
      trial.shadow_map.size = c.size;
    const LightPlan plan = fit_light(trial, light, buffers, measured, nullptr, timeline);
    const std::vector<LightMap> maps = light_maps(trial, buffers, plan, true, 0, timeline);
    edge.push_back(edge_sampling.run(view, width, height, maps, only_light(trial), trial.shadow_map,
                                     timeline));
    sizes.push_back(trial.shadow_map.size);
  }
  single_map = nullptr;  // the trial's; the request's is drawn by its own step
  timeline.set_prefix(outer);
  std::optional<Technique> kept;
  if (last != verdicts_.end()) kept = last->second.picked;
  choose_by_trial(pick, tried, edge, sizes, kept);
  if (keeping_) {
    TrialVerdict& v = verdicts_[light];
    v.tried.clear();
    for (size_t i : tried) v.tried.push_back(pick.candidates[i]);
    v.picked = pick.technique;
    v.frame = frame_;
  }
}

std::vector<LightMap> Workspace::light_maps(const RenderRequest& req, const SceneBuffers& buffers,
                                            const LightPlan& plan, bool render,
                                            uint32_t blur_planes, Timeline& timeline,
                                            RasterLoad* drawn) {
  const Scene& scene = *req.scene;
  const uint32_t size = req.shadow_map.size;
  std::vector<LightMap> maps;
  if (!plan.cube) {
    if (!render) return {{plan.light, &empty_map}};  // texel density needs the matrix only
    // Blur: class instances are drawn into the map (casters or not) so their texels carry
    // their class.
    auto draws =
        make_draws(scene, buffers, glm::mat4(plan.light.world_to_ndc), [&](const Instance& i) {
          const bool drawn =
              i.casts_shadows || (blur_planes > 0 && i.receiver_class != Instance::kNoClass);
          return drawn && (!plan.cull || reaches_into(buffers, i, plan.light.world_to_ndc));
        });
    single_map = &rasterizer.run(buffers, draws, size, size, blur_planes > 0, "shadow_map",
                                 "shadow_map.size", timeline, world_bias(req, plan.light));
    single_map_draws = uint32_t(draws.size());
    if (drawn) *drawn += single_map->load;
    return {{plan.light, &single_map->depth, single_map->version}};
  }
  uint32_t skipped = 0;
  for (int k = 0; k < 6; ++k) {
    const CubeFaceFit& face = plan.faces[k];
    if (!face.rendered) {
      skipped |= 1u << k;
    } else if (!render) {
      maps.push_back({face.setup, &empty_map});
    } else {
      // Only the casters whose boxes reach into the face.
      auto draws =
          make_draws(scene, buffers, glm::mat4(face.setup.world_to_ndc), [&](const Instance& i) {
            return i.casts_shadows && reaches_into(buffers, i, face.setup.world_to_ndc);
          });
      const RasterOutput& out = rasterizer.run(
          buffers, draws, size, size, false, std::string("shadow_map.") + kCubeFaceNames[k],
          "shadow_map.size", timeline, world_bias(req, face.setup));
      if (drawn) *drawn += out.load;
      maps.push_back({face.setup, &out.depth, out.version});
    }
  }
  if (skipped != 0) {  // one launch for the rest: off every map, so lit
    ViewSetup none;
    none.world_to_ndc = glm::dmat4(0.0);
    none.faces = plan.faces[0].setup.faces;
    none.faces.owned = skipped;
    maps.push_back({none, &empty_map});
  }
  return maps;
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

QualityPick Workspace::pick(const RenderRequest& req, const RenderControl& control,
                            Timeline& timeline) {
  if (!control.calibration || !control.candidate_cost)
    throw std::logic_error("a quality goal needs the engine's calibration and cost");
  upload_scene(req, control, keeping_, "scene", timeline);
  scene_uploaded_ = true;
  const std::vector<InstanceBounds> instances = instance_bounds(*req.scene, *scene_);
  const ProbeMeasure measure = probe(req, timeline);
  const double measure_ms =
      load_passes_ms(req, double(req.lights.size()), control.calibration->times().rates);
  const CandidateLoads loads{
      [&](Technique t) { return candidate_loads(req, instances, measure.depth, t, timeline); },
      {measure_ms, measure_ms}};
  return pick_quality(req, instances, measure, *control.calibration, control.candidate_cost, loads);
}

std::array<MapLoads, kQualitySizes.size()> Workspace::candidate_loads(
    const RenderRequest& req, const std::vector<InstanceBounds>& instances,
    const std::optional<DepthRange>& depth, Technique technique, Timeline& timeline) {
  std::array<MapLoads, kQualitySizes.size()> loads;
  constexpr uint32_t kLargest = kQualitySizes.back();  // set up once, summed at each size
  for (size_t i = 0; i < req.lights.size(); ++i) {
    timeline.set_prefix("quality_probe." + light_pass_prefix(req, i));
    const glm::dmat4 m = candidate_matrix(req, i, technique, instances, depth);
    const auto draws = make_draws(*req.scene, *scene_, glm::mat4(m),
                                  [](const Instance& inst) { return inst.casts_shadows; });
    const std::vector<RasterLoad> levels =
        rasterizer.load(*scene_, draws, kLargest, kQualitySizes.size(),
                        std::string("load.") + technique_label(technique), timeline);
    for (size_t k = 0; k < kQualitySizes.size(); ++k)  // level 0: the largest
      loads[k].push_back(levels[kQualitySizes.size() - 1 - k]);
  }
  timeline.set_prefix("");
  return loads;
}

void Workspace::forget_probe() {
  probe_view_ = nullptr;
  probe_depth_.reset();
  probe_maps_.clear();
  probe_hard_test_ = nullptr;
}

ProbeMeasure Workspace::probe(const RenderRequest& req, Timeline& timeline) {
  // The camera view is the request's own: its run takes it (kCameraView) instead of drawing it
  // again.
  const GBuffer& view =
      gbuffer.run(*req.scene, *scene_, req.camera, camera_setup(req.camera), timeline);
  probe_view_ = &view;
  ProbeMeasure measure;
  timeline.set_prefix("quality_probe.");
  // The view-depth range: PSM and LiSPSM fit to it, so their candidates are predicted as they
  // would be drawn; the run takes it. Uniform's fit does not read it: a goal of uniform
  // candidates alone measures none. The first light's hard test measures it where that test is
  // of a single map: it reads the G-buffer the range needs (one read of it instead of two).
  const std::vector<Technique> techniques = quality_techniques(req);
  bool wants_depth = std::any_of(techniques.begin(), techniques.end(),
                                 [](Technique t) { return t != Technique::kUniform; });
  const uint32_t pixels = req.camera.width * req.camera.height;
  const uint32_t strips = (pixels + kPcfStrip - 1) / kPcfStrip;
  std::vector<uint32_t> cells;  // each sample's
  measure.samples = view_samples.run(view, req.camera.width, req.camera.height, timeline, &cells);
  std::vector<double>& shares = measure.boundary;
  const RenderRequest probes = quality_probe(req);
  probe_maps_.assign(req.lights.size(), std::nullopt);
  for (size_t i = 0; i < req.lights.size(); ++i) {
    const RenderRequest probe = for_light(probes, i);
    timeline.set_prefix("quality_probe." + light_pass_prefix(req, i));
    const LightPlan plan = fit_light(probe, uint32_t(i), *scene_, std::nullopt, nullptr, timeline);
    const std::vector<LightMap> maps = light_maps(probe, *scene_, plan, true, 0, timeline);
    if (!plan.cube)
      probe_maps_[i] =
          ProbeMap{plan.light.world_to_ndc, single_map, single_map->version, single_map_draws};
    std::optional<ViewDepthOut> depth;
    if (wants_depth && !plan.cube) depth = depth_range.out(req.camera, strips);
    const cl::Buffer& vis = shadow_test.run(view, pixels, maps, only_light(probe), probe.shadow_map,
                                            timeline, depth ? &*depth : nullptr);
    if (wants_depth) {
      measure.depth =
          depth ? depth_range.read(strips, timeline) : depth_range.run(view, req.camera, timeline);
      probe_depth_ = measure.depth;
      wants_depth = false;
    }
    if (req.lights.size() == 1) probe_hard_test_ = &vis;
    const BoundaryCount count = boundary.run(vis, view, req.camera, req.lights[i], timeline);
    shares.push_back(count.share);
    std::vector<double>& weights = measure.weights.emplace_back();
    for (uint32_t cell : cells) weights.push_back(count.cells.at(cell));
  }
  timeline.set_prefix("");
  return measure;
}

bool Workspace::take_probe_map(const RenderRequest& one, uint32_t index, const LightPlan& light,
                               const Plan& plan, std::vector<LightMap>& maps) {
  if (index >= probe_maps_.size() || !probe_maps_[index]) return false;
  const ProbeMap& p = *probe_maps_[index];
  if (!taken_from_probe(one, plan, StepKind::kRenderMaps) || light.cube ||
      light.light.world_to_ndc != p.world_to_ndc || p.map->version != p.version)
    return false;
  single_map = p.map;
  single_map_draws = p.draws;
  maps = {{light.light, &single_map->depth, single_map->version}};
  return true;
}

RenderResult Workspace::run(const RenderRequest& req, const Plan& plan,
                            const RenderControl& control, Timeline& timeline) {
  const Scene& scene = *req.scene;
  const ViewSetup camera = camera_setup(req.camera);
  const uint32_t pixels = req.camera.width * req.camera.height;
  // Each light's steps read the request narrowed to it (engine/light_request.hpp); a request
  // with no light (POSITION alone) runs the camera's steps only.
  std::vector<RenderRequest> lights;
  for (size_t i = 0; i < req.lights.size(); ++i) lights.push_back(for_light(req, i));
  if (lights.empty()) lights.push_back(req);
  const std::shared_ptr<const SceneBuffers>& buffers = scene_;
  const GBuffer* view = nullptr;
  std::optional<DepthRange> measured;
  RenderResult result;
  result.light_fits.resize(req.lights.size());

  // The current light's resources: its steps run together, ending with its readback.
  uint32_t current = 0;
  LightPlan light;
  std::vector<LightMap> maps;
  const cl::Buffer* vis = nullptr;
  const cl::Buffer* density = nullptr;
  std::map<Resource, const MipChain*> chains;
  std::map<Resource, const SummedAreaTable*> tables;
  bool map_from_probe = false;  // this light's map is its quality probe's
  const auto start_light = [&](uint32_t i) {
    if (!req.lights.empty()) result.light_fits[current] = light.report;
    current = i;
    light = {};
    maps.clear();
    map_from_probe = false;
    vis = density = nullptr;
    chains.clear();
    tables.clear();
    single_map = nullptr;
    blurred = nullptr;
    csm_basis = nullptr;
    atlas_visibility = nullptr;
    atlas_kept = false;
  };
  start_light(0);
  half_ = req.output_format == PixelFormat::kFloat16;
  csm_blocker_depth = std::find(req.products.begin(), req.products.end(), Product::kBlockerDepth) !=
                      req.products.end();
  const uint32_t size = req.shadow_map.size;
  const auto source = [&](Resource r) {  // the texture a mip chain or SAT filters
    switch (r) {
      case Resource::kLightMaps:
        return DeviceTexture{&single_map->depth, size, size, 1};
      case Resource::kAtlas:
        return DeviceTexture{atlas_visibility, atlas.width(), atlas.height(), 1};
      default:
        return DeviceTexture{vis, req.camera.width, req.camera.height, 1};
    }
  };

  std::vector<Texture> textures;
  for (const Step& step : plan.steps) {
    const bool shared = is_shared(step.kind);
    if (!shared && step.light != current) start_light(step.light);
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
      case StepKind::kCameraView:
        view =
            probe_view_ ? probe_view_ : &gbuffer.run(scene, *buffers, req.camera, camera, timeline);
        probe_view_ = nullptr;
        break;
      case StepKind::kDepthRange:
        if (probe_depth_) {  // the probe measured this very view
          measured = *probe_depth_;
          probe_depth_.reset();
          timeline.reuse(pass);
        } else {
          measured = depth_range.run(*view, req.camera, timeline);
        }
        break;
      case StepKind::kFitLight:
        light = fit_light(one, current, *buffers, measured, view, timeline);
        lights[current].shadow_map.size = light.map_size;  // AUTO's PSM cube: its faces'
        // Unrendered: texel density reads their matrices only.
        maps = light_maps(one, *buffers, light, false, 0, timeline);
        break;
      case StepKind::kRenderMaps: {
        map_from_probe = take_probe_map(one, current, light, plan, maps);
        RasterLoad drawn;
        if (map_from_probe) {
          timeline.reuse(pass);
          drawn = single_map->load;
        } else {
          maps = light_maps(one, *buffers, light, true, plan.blur_planes, timeline, &drawn);
        }
        light.report.raster_overlaps = drawn.overlaps;
        light.report.raster_box_pixels = drawn.box_pixels;
        break;
      }
      case StepKind::kBlurPlanes:
        blurred = &blur.classify(*single_map, single_map_draws, size, plan.blur_planes, timeline);
        blur.blur(*blurred, size, size, plan.blur_planes, req.filter.blur.radius,
                  req.filter.blur.passes, timeline);
        break;
      case StepKind::kVisibility:  // a cube: each face decides the pixels it owns
        if (is_atlas_filter(one.filter.kind)) {
          const PcssPass::AtlasInputs in{buffers.get(), &atlas.uvs(), &atlas.instance_tiles(),
                                         &atlas.soft(prefix), atlas.width()};
          vis = &pcss.run_atlas(*view, pixels, only_light(one), in, timeline);
          break;
        }
        if (map_from_probe && probe_hard_test_ && taken_from_probe(req, plan, step.kind)) {
          vis = probe_hard_test_;  // the probe's test of this very map
          timeline.reuse(pass);
          break;
        }
        vis = &visibility(one, plan, *view, pixels, req.camera.width, maps, timeline);
        break;
      case StepKind::kAtlasView:
        atlas_view = &atlas.bake(scene, *buffers, req.atlas, timeline);
        break;
      case StepKind::kAtlasVisibility: {
        // In a sequence the filter and settings are the same every frame: the light and its
        // maps decide the rest.
        AtlasPass::Inputs inputs{only_light(one), {}};
        for (const LightMap& m : maps) inputs.maps.emplace_back(m.depth, m.version);
        if (const cl::Buffer* kept = atlas.kept(prefix, inputs)) {
          timeline.reuse(pass);
          atlas_visibility = kept;
          atlas_kept = true;
          break;
        }
        // The visibility passes' own names under "atlas."; the camera's blocker depth is not
        // the atlas' to write.
        const bool blocker = csm_blocker_depth;
        csm_blocker_depth = false;
        timeline.set_prefix(prefix + "atlas.");
        // The atlas filters prefilter the hard test.
        RenderRequest hard;
        const bool lookup = is_atlas_filter(one.filter.kind);
        if (lookup) hard = one, hard.filter.kind = FilterKind::kHard;
        const cl::Buffer* filtered =
            &visibility(lookup ? hard : one, plan, *atlas_view, atlas.width() * atlas.height(),
                        atlas.width(), maps, timeline);
        timeline.set_prefix(prefix);
        csm_blocker_depth = blocker;
        atlas_visibility = &atlas.finish(*filtered, req.atlas.gutter, prefix, inputs, timeline);
        break;
      }
      case StepKind::kAtlasSoften: {  // made with this light's atlas, so kept with it
        if (atlas_kept) {
          timeline.reuse(pass);
          break;
        }
        const LightMap& m = maps.at(0);  // uniform maps only
        const uint32_t texels = atlas.width() * atlas.height();
        pcss.penumbra(*atlas_view, texels, atlas.width(), *m.depth, m.setup, only_light(one),
                      one.shadow_map, one.filter.pcss, atlas.penumbra(prefix), timeline);
        const bool sat_lookup = one.filter.kind == FilterKind::kAtlasSat;
        PcssPass::AtlasPrefiltered in;
        in.half_width = &atlas.penumbra(prefix);
        in.sat = sat_lookup ? tables.at(Resource::kAtlasSat) : nullptr;
        in.level0 = atlas_visibility;
        in.mips = sat_lookup ? nullptr : chains.at(Resource::kAtlasMips);
        in.texel_area = &atlas.texel_area();
        in.width = atlas.width(), in.height = atlas.height(), in.tile = atlas.tile();
        pcss.soften(*atlas_view, m.setup, only_light(one), one.shadow_map, in, atlas.soft(prefix),
                    timeline);
        break;
      }
      case StepKind::kTexelDensity:
        density =
            &texel_density.run(*view, req.camera, camera, maps, one.shadow_map.size, timeline);
        break;
      case StepKind::kMips:
        if (const MipChain* last = kept_atlas_prefilter(step, prefix) ? mips.last(pass) : nullptr) {
          timeline.reuse(pass);
          chains[step.writes[0]] = last;
          break;
        }
        chains[step.writes[0]] = &mips.run(source(step.reads[0]), pass, timeline);
        break;
      case StepKind::kSat: {  // the atlas' with its coverage: its empty texels are not zeros
        const Resource r = step.reads[0];
        if (const SummedAreaTable* last =
                kept_atlas_prefilter(step, prefix) ? sat.last(pass) : nullptr) {
          timeline.reuse(pass);
          tables[step.writes[0]] = last;
          break;
        }
        const DeviceTexture src =
            r == Resource::kAtlas ? atlas.coverage(*atlas_visibility, timeline) : source(r);
        tables[step.writes[0]] = &sat.run(src, pass, timeline);
        break;
      }
      case StepKind::kCsmBasis: {
        if (light.cube) break;  // a basis per face, each before its face's lookups (face_basis)
        const CsmSettings& c = req.filter.csm;
        const CsmInputs inputs{single_map, single_map->version, light.light.depth,
                               c,          plan.csm_blocker,    plan.csm_prefilter};
        if (keeping_ && csm_made_from_ == inputs) {
          timeline.reuse(pass);
          csm_basis = &csm.basis();
          break;
        }
        csm_made_from_.reset();
        csm_basis = &csm.build(single_map->depth, size, inputs.depth, c.terms,
                               c.storage == CsmStorage::kFloat16, plan.csm_blocker,
                               plan.csm_prefilter, timeline);
        if (keeping_) csm_made_from_ = inputs;
        break;
      }
      case StepKind::kReadback: {
        for (Texture& t :
             read_products(one, current == 0, light_texture_suffix(req, current), light, camera,
                           maps, vis, view, density, chains, tables, source, timeline)) {
          if (per_light(t.kind)) t.light = current;
          textures.push_back(std::move(t));
        }
        break;
      }
    }
  }
  start_light(current);  // keeps the last light's report
  // Product by product as asked for; each product's lights in order (stable: mips by level).
  const auto rank = [&](const Texture& t) {
    return std::find(req.products.begin(), req.products.end(), t.kind) - req.products.begin();
  };
  std::stable_sort(textures.begin(), textures.end(),
                   [&](const Texture& a, const Texture& b) { return rank(a) < rank(b); });
  result.textures = std::move(textures);
  runtime.finish();
  result.passes = timeline.passes();
  result.reused = timeline.reused();
  if (control.profile) result.timings = timeline.timings();
  return result;
}

std::vector<Texture> Workspace::read_products(
    const RenderRequest& req, bool shared, const std::string& sfx, const LightPlan& light,
    const ViewSetup& camera, const std::vector<LightMap>& maps, const cl::Buffer* vis,
    const GBuffer* view, const cl::Buffer* density,
    const std::map<Resource, const MipChain*>& chains,
    const std::map<Resource, const SummedAreaTable*>& tables,
    const std::function<DeviceTexture(Resource)>& source, Timeline& timeline) {
  const uint32_t size = req.shadow_map.size, w = req.camera.width, h = req.camera.height;
  std::vector<Texture> out;
  for (Product p : req.products) {
    if (!per_light(p) && !shared) continue;
    std::vector<Texture> ts;
    switch (p) {
      case Product::kShadowMap:
        ts.push_back(light.cube ? read_cube(maps, size, "shadowmap_cube" + sfx, timeline)
                                : read_texture(single_map->depth, "shadowmap" + sfx, p, size, size,
                                               1, timeline));
        break;
      case Product::kShadowMapMips:
        ts = read_mips(source(Resource::kLightMaps), *chains.at(Resource::kMapMips),
                       "shadowmap" + sfx, p, timeline);
        break;
      case Product::kShadowMapSat:
        ts.push_back(read_sat(*tables.at(Resource::kMapSat), "shadowmap" + sfx, p, timeline));
        break;
      case Product::kVisibility:
        ts.push_back(read_texture(*vis, "visibility" + sfx, p, w, h, 1, timeline));
        break;
      case Product::kVisibilityMips:
        ts = read_mips(source(Resource::kVisibility), *chains.at(Resource::kVisibilityMips),
                       "visibility" + sfx, p, timeline);
        break;
      case Product::kVisibilitySat:
        ts.push_back(
            read_sat(*tables.at(Resource::kVisibilitySat), "visibility" + sfx, p, timeline));
        break;
      case Product::kTexelDensity:
        ts.push_back(read_texture(*density, "texel_density" + sfx, p, w, h, 1, timeline));
        break;
      case Product::kPosition:
        ts.push_back(read_texture(view->position, "position", p, w, h, 3, timeline));
        break;
      case Product::kCsmBasis: {
        ts.push_back(read_texture(csm.pack(*csm_basis, timeline), "csm_basis" + sfx, p, size, size,
                                  csm_basis->channels(), timeline));
        ts.back().channel_names = csm_channel_names(csm_basis->terms, csm_basis->blocker);
        ts.back().depth_mapping = csm_depth_mapping_text(csm_basis->depth);
        ts.back().csm_terms = csm_basis->terms;
        ts.back().csm_storage = req.filter.csm.storage;
        break;
      }
      case Product::kBlockerDepth:
        ts.push_back(read_texture(csm.blocker(), "blocker_depth" + sfx, p, w, h, 1, timeline));
        ts.back().depth_mapping = csm_depth_mapping_text(csm_basis->depth);
        break;
      case Product::kShadowAtlas:  // in UV space: no matrix places it
        ts.push_back(read_texture(*atlas_visibility, "shadow_atlas" + sfx, p, atlas.width(),
                                  atlas.height(), 1, timeline));
        break;
      case Product::kShadowAtlasMips:
        ts = read_mips(source(Resource::kAtlas), *chains.at(Resource::kAtlasMips),
                       "shadow_atlas" + sfx, p, timeline);
        break;
      case Product::kAtlasUvs:  // the meshes the engine laid out, one texture each
        for (uint32_t m : req.generated_layouts) {
          const MeshRange& range = scene_->meshes()[m];
          ts.push_back(read_texture(atlas.corner_uvs(*scene_, range, timeline),
                                    "atlas_uvs_mesh" + std::to_string(m), p, 3,
                                    range.triangle_count, 2, timeline));
          ts.back().channel_names = {"u", "v"};
          ts.back().mesh = m;
        }
        break;
      case Product::kShadowAtlasSat:
        ts.push_back(read_sat(*tables.at(Resource::kAtlasSat), "shadow_atlas" + sfx, p, timeline));
        ts.back().channel_names = {"visibility", "coverage"};
        break;
    }
    const bool light_space = p == Product::kShadowMap || p == Product::kShadowMapMips ||
                             p == Product::kShadowMapSat || p == Product::kCsmBasis;
    const bool in_uv_space = p == Product::kShadowAtlas || p == Product::kShadowAtlasMips ||
                             p == Product::kShadowAtlasSat;
    for (Texture& t : ts) {
      // No matrix places the atlas: its tiles do (in level-0 texels, so on level 0 only).
      if (in_uv_space && &t == &ts.front()) t.atlas_tiles = atlas.tiles();
      // A cube's faces carry their own matrices; mip levels keep the source's (NDC x, y run
      // 0..1 across every level).
      if (t.cube_faces.empty() && t.faces != 0 && !in_uv_space && p != Product::kAtlasUvs) {
        t.world_to_ndc = glm::mat4(light_space ? light.light.world_to_ndc : camera.world_to_ndc);
        t.world_to_camera = glm::mat4(light_space ? light.light.view : camera.view);
      }
      out.push_back(std::move(t));
    }
  }
  return out;
}

}  // namespace shadow
