#include "engine/run/light_fitter.hpp"

#include <algorithm>
#include <string>

#include "engine/light/lispsm_fit.hpp"
#include "engine/plan/filter.hpp"
#include "engine/plan/light_request.hpp"
#include "engine/plan/plan.hpp"

namespace shadow {
namespace {

// Whether the instance's box reaches into the frustum of `world_to_ndc`.
bool reaches_into(const SceneBuffers& buffers, const Instance& i, const glm::dmat4& world_to_ndc) {
  return may_be_visible(transform_bounds(buffers.meshes()[i.mesh].bounds, glm::dmat4(i.transform)),
                        world_to_ndc);
}

// The world-space caster bias (Kozlov 14.3.1) of one light map; the camera view has none.
WorldBias world_bias(const RenderRequest& req, const ViewSetup& light, uint32_t map_size) {
  WorldBias bias;
  bias.world_to_ndc = glm::mat4(light.world_to_ndc);
  bias.light = light_item(only_light(req));
  bias.constant = req.shadow_map.bias_world_constant;
  bias.texel = req.shadow_map.bias_world_texel;
  bias.map_size = map_size;
  return bias;
}

}  // namespace

std::vector<InstanceBounds> instance_bounds(const Scene& scene, const SceneBuffers& buffers) {
  std::vector<InstanceBounds> out;
  for (const Instance& inst : scene.instances) {
    out.push_back({transform_bounds(buffers.meshes()[inst.mesh].bounds, glm::dmat4(inst.transform)),
                   inst.casts_shadows, inst.receives_shadows});
  }
  return out;
}

LightFitter::LightFitter(Rasterizer& rasterizer, ViewSamplesPass& view_samples,
                         LightDistancePass& light_distance, EdgeSamplingPass& edge_sampling,
                         const cl::Buffer& empty_map)
    : rasterizer_(rasterizer),
      view_samples_(view_samples),
      light_distance_(light_distance),
      edge_sampling_(edge_sampling),
      empty_map_(empty_map) {}

void LightFitter::forget_trials() {
  frame_ = 0;
  verdicts_.clear();
}

double LightFitter::nearest_caster(const RenderRequest& req, const SceneBuffers& buffers,
                                   Timeline& timeline) {
  const std::vector<DrawItem> casters = make_draws(
      *req.scene, buffers, glm::mat4(1.0f), [](const Instance& i) { return i.casts_shadows; });
  return light_distance_.run(buffers, casters, only_light(req).position, timeline);
}

std::array<CubeFaceFit, 6> LightFitter::fit_point_cube(const RenderRequest& req,
                                                       const SceneBuffers& buffers,
                                                       const std::vector<InstanceBounds>& bounds,
                                                       Timeline& timeline,
                                                       std::optional<double> distance) {
  if (!distance) distance = nearest_caster(req, buffers, timeline);
  return fit_cube(only_light(req), req.camera, bounds, req.shadow_map.size,
                  filter_reach(req.filter), *distance, req.shadow_map.fit)
      .faces;
}

LightPlan LightFitter::fit(const RenderRequest& req, uint32_t light_index,
                           const SceneBuffers& buffers, const std::optional<DepthRange>& measured,
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
    if (view) samples = view_samples_.run(*view, req.camera.width, req.camera.height, timeline);
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
  } else if (technique == Technique::kVirtual) {
    plan.virtual_levels = fit_virtual(req, buffers, bounds, timeline);
    const VirtualLevels& v = *plan.virtual_levels;
    plan.light = v.levels.front().setup;
    report.light_case =
        v.faces == 0 ? "virtual: directional, levels " + std::to_string(v.levels.front().level) +
                           ".." + std::to_string(v.levels.back().level)
        : v.faces == 1 ? "virtual: spot, mips 0.." + std::to_string(v.mips - 1)
                       : "virtual: point, 6 faces, mips 0.." + std::to_string(v.mips - 1);
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

VirtualLevels LightFitter::fit_virtual(const RenderRequest& req, const SceneBuffers& buffers,
                                       const std::vector<InstanceBounds>& bounds,
                                       Timeline& timeline) {
  const Light& light = only_light(req);
  const uint32_t texels = req.shadow_map.size;
  if (light.type == LightType::kDirectional) {
    Bounds scene;
    for (const InstanceBounds& b : bounds) scene.extend(b.world);
    return fit_directional_clipmap(light, req.camera, scene, texels,
                                   req.shadow_map.virtual_lod_bias, virtual_reach(req.filter));
  }
  // Fitted to the scene, not the view, so that a sequence keeps the pages.
  const int mips = virtual_mips(light.type, texels);
  if (light.type == LightType::kSpot)
    return perspective_levels({fit_uniform_light(light, req.camera, bounds, MapFit::kScene)}, {},
                              texels, mips);
  // The faces' guard bands hold the filter's reach in the coarsest mip's texels, so in every mip.
  const CubeFit cube =
      fit_cube(light, req.camera, bounds, texels >> (mips - 1), filter_reach(req.filter),
               nearest_caster(req, buffers, timeline), MapFit::kScene);
  std::vector<ViewSetup> faces;
  for (const CubeFaceFit& f : cube.faces) faces.push_back(f.setup);
  return perspective_levels(faces, cube.faces[0].setup.faces, texels, mips);
}

void LightFitter::try_candidates(const RenderRequest& req, uint32_t light,
                                 const SceneBuffers& buffers,
                                 const std::optional<DepthRange>& measured, const GBuffer& view,
                                 AutoPick& pick, Timeline& timeline) {
  const std::vector<size_t> tried = trial_candidates(pick);
  if (tried.empty()) return;
  const bool keeping = cache_ && cache_->keeping();
  const auto last = keeping ? verdicts_.find(light) : verdicts_.end();
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
    const LightPlan plan = fit(trial, light, buffers, measured, nullptr, timeline);
    const DrawnMaps drawn = draw(trial, buffers, plan, true, 0, timeline);
    edge.push_back(edge_sampling_.run(view, width, height, drawn.maps, only_light(trial),
                                      trial.shadow_map, timeline));
    sizes.push_back(trial.shadow_map.size);
  }
  timeline.set_prefix(outer);
  std::optional<Technique> kept;
  if (last != verdicts_.end()) kept = last->second.picked;
  choose_by_trial(pick, tried, edge, sizes, kept);
  if (keeping) {
    TrialVerdict& v = verdicts_[light];
    v.tried.clear();
    for (size_t i : tried) v.tried.push_back(pick.candidates[i]);
    v.picked = pick.technique;
    v.frame = frame_;
  }
}

DrawnMaps LightFitter::draw(const RenderRequest& req, const SceneBuffers& buffers,
                            const LightPlan& plan, bool render, uint32_t blur_planes,
                            Timeline& timeline) {
  const Scene& scene = *req.scene;
  const uint32_t size = req.shadow_map.size;
  DrawnMaps out;
  if (!plan.cube) {
    if (!render) {  // texel density needs the matrix only
      out.maps = {{plan.light, &empty_map_}};
      return out;
    }
    // Blur: class instances are drawn into the map (casters or not) so their texels carry
    // their class.
    auto draws =
        make_draws(scene, buffers, glm::mat4(plan.light.world_to_ndc), [&](const Instance& i) {
          const bool drawn =
              i.casts_shadows || (blur_planes > 0 && i.receiver_class != Instance::kNoClass);
          return drawn && (!plan.cull || reaches_into(buffers, i, plan.light.world_to_ndc));
        });
    out.single = &rasterizer_.run(buffers, draws, size, size, blur_planes > 0, "shadow_map",
                                  "shadow_map.size", timeline, world_bias(req, plan.light, size));
    out.single_draws = uint32_t(draws.size());
    out.load += out.single->load;
    out.maps = {{plan.light, &out.single->depth, out.single->version}};
    return out;
  }
  uint32_t skipped = 0;
  for (int k = 0; k < 6; ++k) {
    const CubeFaceFit& face = plan.faces[k];
    if (!face.rendered) {
      skipped |= 1u << k;
    } else if (!render) {
      out.maps.push_back({face.setup, &empty_map_});
    } else {
      // Only the casters whose boxes reach into the face.
      auto draws =
          make_draws(scene, buffers, glm::mat4(face.setup.world_to_ndc), [&](const Instance& i) {
            return i.casts_shadows && reaches_into(buffers, i, face.setup.world_to_ndc);
          });
      const RasterOutput& face_map = rasterizer_.run(
          buffers, draws, size, size, false, std::string("shadow_map.") + kCubeFaceNames[k],
          "shadow_map.size", timeline, world_bias(req, face.setup, size));
      out.load += face_map.load;
      out.maps.push_back({face.setup, &face_map.depth, face_map.version});
    }
  }
  if (skipped != 0) {  // one launch for the rest: off every map, so lit
    ViewSetup none;
    none.world_to_ndc = glm::dmat4(0.0);
    none.faces = plan.faces[0].setup.faces;
    none.faces.owned = skipped;
    out.maps.push_back({none, &empty_map_});
  }
  return out;
}

DrawnMaps LightFitter::draw_pages(const RenderRequest& req, const SceneBuffers& buffers,
                                  const VirtualPagesPass& pages, const VirtualMap& map,
                                  Timeline& timeline) {
  const VirtualLevels& c = map.layout;
  DrawnMaps out;
  for (size_t i = 0; i < c.levels.size(); ++i) {
    if (map.level_drawn.at(i) == 0) continue;  // nothing to draw: kept, or no page
    const ViewSetup& level = c.levels[i].setup;
    auto draws =
        make_draws(*req.scene, buffers, glm::mat4(level.world_to_ndc), [&](const Instance& inst) {
          return inst.casts_shadows && reaches_into(buffers, inst, level.world_to_ndc);
        });
    const PageTarget target = pages.target(map, uint32_t(i));
    const uint32_t texels = c.extent(i);  // a dense map's of the level's window
    out.load += rasterizer_
                    .run(buffers, draws, texels, texels, false, "shadow_map", "shadow_map.size",
                         timeline, world_bias(req, level, texels), &target)
                    .load;
  }
  out.maps = {{c.levels.front().setup, &pages.pool(), 0, &map}};
  return out;
}

}  // namespace shadow
