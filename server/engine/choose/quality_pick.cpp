#include "engine/choose/quality_pick.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "engine/choose/auto_pick.hpp"
#include "engine/plan/filter.hpp"
#include "engine/plan/plan.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

// The predicted error of `technique` at each size over the probe's samples: the worst light's,
// times the calibration's error margin at that size.
std::array<double, kQualitySizes.size()> errors(const RenderRequest& r, Technique technique,
                                                const std::vector<InstanceBounds>& instances,
                                                const ProbeMeasure& probe,
                                                const Calibration& calibration) {
  std::array<double, kQualitySizes.size()> worst{};
  const std::vector<Sample>& samples = probe.samples;
  if (samples.empty()) return worst;
  const glm::dmat4 cam = camera_setup(r.camera).world_to_ndc;
  for (size_t i = 0; i < r.lights.size(); ++i) {
    const Light& light = r.lights[i];
    const glm::dmat4 m = candidate_matrix(r, i, technique, instances, probe.depth);
    // The samples' weights: their cells' boundary pixels, else (none near any) all alike.
    std::vector<double> weight(samples.size(), 1.0);
    if (i < probe.weights.size()) {
      const std::vector<double>& w = probe.weights[i];
      if (w.size() != samples.size()) throw std::logic_error("quality probe: a weight per sample");
      double total = 0;
      for (double x : w) total += x;
      if (total > 0) weight = w;
    }
    std::array<double, kQualitySizes.size()> sum{};
    double total_weight = 0;
    for (size_t j = 0; j < samples.size(); ++j) {
      const Sample& s = samples[j];
      total_weight += weight[j];
      if (!faces_light(light, s)) continue;  // an attached shadow: no map misclassifies it
      // At one texel per map the footprint is size times that of a size^2 map.
      const double f1 = texel_footprint(m, 1, cam, r.camera.width, r.camera.height, s.p, s.n);
      for (size_t k = 0; k < kQualitySizes.size(); ++k)
        sum[k] += weight[j] * calibration.per_boundary_at(technique, f1 / kQualitySizes[k]);
    }
    for (size_t k = 0; k < kQualitySizes.size(); ++k)
      worst[k] = std::max(worst[k], probe.boundary.at(i) * sum[k] / total_weight);
  }
  for (size_t k = 0; k < kQualitySizes.size(); ++k)
    worst[k] *= calibration.error_margin(technique, kQualitySizes[k]);
  return worst;
}

}  // namespace

bool meets_goal(const QualityCandidate& c, const Quality& goal) {
  return goal.goal == Quality::Goal::kMaxError ? c.predicted_error <= goal.value
                                               : c.predicted_device_ms <= goal.value;
}

const QualityCandidate& choose_candidate(const std::vector<QualityCandidate>& candidates,
                                         const Quality& goal) {
  const bool by_error = goal.goal == Quality::Goal::kMaxError;
  // Candidates are in (technique, size) order, so a strict comparison keeps the earlier on ties;
  // sizes first: the smaller of two equal candidates wins. Those that meet an error bound rank
  // by their typical time, what they cost on average; a budget's fallback, the fastest, by the
  // 90th percentile the budget is held to.
  const auto better = [&](const QualityCandidate& a, const QualityCandidate& b, bool met) {
    const bool by_time = met == by_error;
    const auto time = [&](const QualityCandidate& c) {
      return by_error ? c.typical_device_ms : c.predicted_device_ms;
    };
    const double pa = by_time ? time(a) : a.predicted_error,
                 pb = by_time ? time(b) : b.predicted_error;
    if (pa != pb) return pa < pb;
    return a.size < b.size;
  };
  const QualityCandidate* best = nullptr;
  for (bool met : {true, false}) {
    for (const QualityCandidate& c : candidates)
      if (meets_goal(c, goal) == met && (!best || better(c, *best, met))) best = &c;
    if (best) break;
  }
  return *best;
}

std::vector<Technique> quality_techniques(const RenderRequest& request) {
  std::vector<LightType> types;
  for (const Light& l : request.lights) types.push_back(l.type);
  return single_map_candidates(types, request.filter.kind);
}

glm::dmat4 candidate_matrix(const RenderRequest& request, size_t light, Technique technique,
                            const std::vector<InstanceBounds>& instances,
                            const std::optional<DepthRange>& depth) {
  return fitted_matrix(technique, request.lights.at(light), request.camera, instances, depth);
}

QualityPick pick_quality(const RenderRequest& request, const std::vector<InstanceBounds>& instances,
                         const ProbeMeasure& probe, const Calibration& calibration,
                         const CandidateCost& cost, const CandidateLoads& loads) {
  const std::vector<double>& boundary = probe.boundary;
  std::vector<QualityCandidate> candidates;
  // Each candidate's request, its size's index and its time without what the measures cost.
  struct Priced {
    RenderRequest request;
    size_t size_index;
    PredictedTime own;
  };
  std::vector<Priced> priced;
  for (Technique t : quality_techniques(request)) {
    const auto e = errors(request, t, instances, probe, calibration);
    for (size_t k = 0; k < kQualitySizes.size(); ++k) {
      QualityPick trial;
      trial.technique = t;
      trial.size = kQualitySizes[k];
      RenderRequest c = with_pick(request, trial);
      if (const std::optional<CandidatePrice> p = cost(c, {})) {
        const bool draws_none = taken_from_probe(c, p->plan, StepKind::kRenderMaps);
        const PredictedTime& ms = p->time;
        candidates.push_back({t, kQualitySizes[k], e[k], ms.p90_ms, ms.typical_ms, draws_none});
        priced.push_back({std::move(c), k, ms});
      }
    }
  }
  if (candidates.empty())
    throw ResourceExhausted("quality",
                            "the server would refuse every technique and map size "
                            "(output or cost limits): ask for less");
  const Quality& q = request.quality;
  const bool by_error = q.goal == Quality::Goal::kMaxError;
  PredictedTime measures;  // the loads measured so far
  const QualityCandidate* chosen = &choose_candidate(candidates, q);
  while (!chosen->raster_load_priced && loads.measure) {
    const Technique t = chosen->technique;
    const std::array<MapLoads, kQualitySizes.size()> load = loads.measure(t);
    measures += loads.each;
    for (size_t i = 0; i < candidates.size(); ++i) {
      QualityCandidate& c = candidates[i];
      Priced& p = priced[i];
      if (c.technique == t && !c.raster_load_priced) {
        // Admitted without its load, so admitted with it: admission does not price loads.
        if (const std::optional<CandidatePrice> again = cost(p.request, load[p.size_index]))
          p.own = again->time;
        c.raster_load_priced = true;
      }
      c.predicted_device_ms = p.own.p90_ms + measures.p90_ms;
      c.typical_device_ms = p.own.typical_ms + measures.typical_ms;
    }
    chosen = &choose_candidate(candidates, q);
  }
  const QualityCandidate& best = *chosen;
  QualityPick pick;
  pick.technique = best.technique;
  pick.size = best.size;
  pick.predicted_error = best.predicted_error;
  pick.predicted_device_ms = best.predicted_device_ms;
  pick.goal_met = meets_goal(best, q);
  pick.boundary_share = boundary;
  char text[160];
  std::snprintf(text, sizeof text, "%s %.3g%s: %s %u, predicted %.3f%% in %.0f ms (%s); ",
                by_error ? "max_error" : "max_device_ms", by_error ? 100 * q.value : q.value,
                by_error ? "%" : " ms", technique_label(pick.technique), pick.size,
                100 * pick.predicted_error, pick.predicted_device_ms,
                pick.goal_met ? "meets the goal" : "nothing predicted to meet it: the closest");
  pick.reason = text;
  pick.reason += "boundary share";
  for (size_t i = 0; i < boundary.size(); ++i) {
    std::snprintf(text, sizeof text, "%s%.2f%%", i ? " / " : " ", 100 * boundary[i]);
    pick.reason += text;
  }
  pick.reason += "; ";
  for (const QualityCandidate& c : candidates) {
    const bool lower_bound = loads.measure && !c.raster_load_priced;  // its load not measured
    std::snprintf(text, sizeof text, "%s%s %u %.3f%% %s%.0f ms", &c == &candidates[0] ? "" : ", ",
                  technique_label(c.technique), c.size, 100 * c.predicted_error,
                  lower_bound ? ">=" : "", c.predicted_device_ms);
    pick.reason += text;
  }
  pick.candidates = std::move(candidates);
  return pick;
}

RenderRequest quality_probe(const RenderRequest& request) {
  RenderRequest r = request;
  r.quality = {};
  r.shadow_map.technique = Technique::kUniform;
  r.shadow_map.size = kQualityProbeSize;
  r.filter = {};  // the hard test
  r.products = {Product::kVisibility};
  return r;
}

bool taken_from_probe(const RenderRequest& picked, const Plan& plan, StepKind kind) {
  const bool probes_maps = picked.shadow_map.technique == Technique::kUniform &&
                           picked.shadow_map.size == kQualityProbeSize && plan.blur_planes == 0;
  if (kind == StepKind::kRenderMaps) return probes_maps;
  if (kind == StepKind::kVisibility)
    return probes_maps && picked.lights.size() == 1 &&
           filter_facts(picked.filter.kind).lookup == FilterFacts::Lookup::kShadowTest;
  return false;
}

RenderRequest with_pick(const RenderRequest& request, const QualityPick& pick) {
  RenderRequest r = request;
  r.quality = {};
  r.shadow_map.technique = pick.technique;
  r.shadow_map.size = pick.size;
  return r;
}

}  // namespace shadow
