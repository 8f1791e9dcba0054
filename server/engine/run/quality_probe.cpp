#include "engine/run/quality_probe.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "engine/choose/calibration.hpp"
#include "engine/plan/light_request.hpp"

namespace shadow {

QualityProbe::QualityProbe(GBufferPass& gbuffer, ViewSamplesPass& view_samples,
                           ShadowTestPass& shadow_test, DepthRangePass& depth_range,
                           BoundaryPass& boundary, Rasterizer& rasterizer, LightFitter& fitter)
    : gbuffer_(gbuffer),
      view_samples_(view_samples),
      shadow_test_(shadow_test),
      depth_range_(depth_range),
      boundary_(boundary),
      rasterizer_(rasterizer),
      fitter_(fitter) {}

QualityProbe::Picked QualityProbe::pick(const RenderRequest& req, const SceneBuffers& scene,
                                        const Calibration& calibration, const CandidateCost& cost,
                                        Timeline& timeline) {
  const std::vector<InstanceBounds> instances = instance_bounds(*req.scene, scene);
  const ProbeMeasure measure = probe(req, scene, timeline);
  const double measure_ms =
      load_passes_ms(req, double(req.lights.size()), calibration.times().rates);
  const CandidateLoads loads{[&](Technique t) {
                               return candidate_loads(req, scene, instances, measure.depth, t,
                                                      timeline);
                             },
                             {measure_ms, measure_ms}};
  Picked picked;
  picked.quality = pick_quality(req, instances, measure, calibration, cost, loads);
  picked.request = with_pick(req, picked.quality);
  // The pick's candidate was priced, so it is priced again: its plan.
  const std::optional<CandidatePrice> price = cost(picked.request, {});
  if (!price) throw std::logic_error("the goal picked a candidate the server refuses");
  picked.plan = price->plan;
  return picked;
}

std::array<MapLoads, kQualitySizes.size()> QualityProbe::candidate_loads(
    const RenderRequest& req, const SceneBuffers& scene,
    const std::vector<InstanceBounds>& instances, const std::optional<DepthRange>& depth,
    Technique technique, Timeline& timeline) {
  std::array<MapLoads, kQualitySizes.size()> loads;
  constexpr uint32_t kLargest = kQualitySizes.back();  // set up once, summed at each size
  for (size_t i = 0; i < req.lights.size(); ++i) {
    timeline.set_prefix("quality_probe." + light_pass_prefix(req, i));
    const glm::dmat4 m = candidate_matrix(req, i, technique, instances, depth);
    const auto draws = make_draws(*req.scene, scene, glm::mat4(m),
                                  [](const Instance& inst) { return inst.casts_shadows; });
    const std::vector<RasterLoad> levels =
        rasterizer_.load(scene, draws, kLargest, kQualitySizes.size(),
                         std::string("load.") + technique_label(technique), timeline);
    for (size_t k = 0; k < kQualitySizes.size(); ++k)  // level 0: the largest
      loads[k].push_back(levels[kQualitySizes.size() - 1 - k]);
  }
  timeline.set_prefix("");
  return loads;
}

void QualityProbe::forget() {
  view_ = nullptr;
  depth_.reset();
  maps_.clear();
  hard_test_ = nullptr;
}

ProbeMeasure QualityProbe::probe(const RenderRequest& req, const SceneBuffers& scene,
                                 Timeline& timeline) {
  // The camera view is the request's own: its run takes it (kCameraView) instead of drawing it
  // again.
  const GBuffer& view =
      gbuffer_.run(*req.scene, scene, req.camera, camera_setup(req.camera), timeline);
  view_ = &view;
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
  measure.samples = view_samples_.run(view, req.camera.width, req.camera.height, timeline, &cells);
  std::vector<double>& shares = measure.boundary;
  const RenderRequest probes = quality_probe(req);
  maps_.assign(req.lights.size(), std::nullopt);
  for (size_t i = 0; i < req.lights.size(); ++i) {
    const RenderRequest probe = for_light(probes, i);
    timeline.set_prefix("quality_probe." + light_pass_prefix(req, i));
    const LightPlan plan = fitter_.fit(probe, uint32_t(i), scene, std::nullopt, nullptr, timeline);
    const DrawnMaps drawn = fitter_.draw(probe, scene, plan, true, 0, timeline);
    if (!plan.cube)
      maps_[i] = ProbeMap{plan.light.world_to_ndc, drawn.single, drawn.single->version,
                          drawn.single_draws};
    std::optional<ViewDepthOut> depth;
    if (wants_depth && !plan.cube) depth = depth_range_.out(req.camera, strips);
    const cl::Buffer& vis = shadow_test_.run(view, pixels, drawn.maps, only_light(probe),
                                             probe.shadow_map, timeline, depth ? &*depth : nullptr);
    if (wants_depth) {
      measure.depth = depth ? depth_range_.read(strips, timeline)
                            : depth_range_.run(view, req.camera, timeline);
      depth_ = measure.depth;
      wants_depth = false;
    }
    if (req.lights.size() == 1) hard_test_ = &vis;
    const BoundaryCount count = boundary_.run(vis, view, req.camera, req.lights[i], timeline);
    shares.push_back(count.share);
    std::vector<double>& weights = measure.weights.emplace_back();
    for (uint32_t cell : cells) weights.push_back(count.cells.at(cell));
  }
  timeline.set_prefix("");
  return measure;
}

bool QualityProbe::take_map(const RenderRequest& one, uint32_t index, const Plan& plan,
                            LightResources& light) {
  if (index >= maps_.size() || !maps_[index]) return false;
  const ProbeMap& p = *maps_[index];
  const LightPlan& fit = light.fit;
  if (!taken_from_probe(one, plan, StepKind::kRenderMaps) || fit.cube ||
      fit.light.world_to_ndc != p.world_to_ndc || p.map->version != p.version)
    return false;
  light.single_map = p.map;
  light.single_map_draws = p.draws;
  light.maps = {{fit.light, &p.map->depth, p.map->version}};
  return true;
}

}  // namespace shadow
