#include "engine/choose/price.hpp"

#include <algorithm>
#include <limits>

#include "engine/cl/runtime.hpp"
#include "engine/plan/cost.hpp"
#include "engine/plan/sequence.hpp"
#include "wire/errors.hpp"
#include "wire/units.hpp"

namespace shadow {

uint64_t pledged_bytes(uint64_t device_bytes, uint64_t budget_bytes) {
  return std::min(cl::Runtime::grown(device_bytes), budget_bytes);
}

Price price_request(const RenderRequest& request, const PriceLimits& limits, bool with_reply,
                    uint64_t held_bytes) {
  validate(request, limits.validation);
  Price p;
  p.plan = make_plan(request);
  // A quality goal's candidates are admitted one by one (pick_quality); the reply is reserved
  // for the largest.
  const bool goal = request.quality.goal != Quality::Goal::kNone;
  const uint64_t budget = limits.budget_bytes;
  if (!goal) {
    const CostEstimate cost = estimate_cost(request, p.plan);
    p.ms = cost.ms, p.driver = cost.driver;
    p.device_bytes = cost.device_bytes;
    admit(cost, limits.max_request_ms, budget);
  }
  if (with_reply) {
    RenderRequest largest = request;
    largest.shadow_map.size = kQualitySizes.back();
    p.reply_bytes = output_bytes(goal ? largest : request);
  }
  // A goal's probe runs before any candidate: admitted first, its time added to each
  // candidate's. Admission prices at its own rates, the camera view counted twice (on the high
  // side) and the probe's own buffers, a 512^2 map per light, left out; the pick predicts at the
  // calibration's typical rates, without the probe's camera view, which the run takes over.
  if (goal) {
    const RenderRequest probe = quality_probe(request);
    const Plan probe_plan = make_plan(probe);
    try {
      // Admitted as if it set up every candidate technique's map per light to measure their
      // raster loads; the pick counts the measures it takes (pick_quality).
      const double load_maps = double(quality_techniques(request).size() * request.lights.size());
      CostEstimate e = estimate_cost(probe, probe_plan);
      e.ms += load_passes_ms(request, load_maps);
      admit(e, limits.max_request_ms, budget);
      p.probe_ms = p.ms = e.ms;
      p.driver = e.driver;
      p.device_bytes = e.device_bytes;
      Plan beyond_view = probe_plan;
      std::erase_if(beyond_view.steps,
                    [](const Step& step) { return step.kind == StepKind::kCameraView; });
      p.probe_predicted = limits.calibration->predict_time(probe, beyond_view);
    } catch (const ResourceExhausted& e) {
      throw ResourceExhausted("quality", "even the goal's probe (the hard test against a " +
                                             std::to_string(kQualityProbeSize) +
                                             "^2 uniform map) is over a limit: " + e.what());
    }
  }
  // What can never fit is refused before it waits; the rest waits for its share.
  const uint64_t need = cl::Runtime::grown(p.device_bytes);
  const uint64_t pledge = pledged_bytes(p.device_bytes, budget);
  if (p.reply_bytes > budget - pledge ||
      held_bytes > budget - pledge - p.reply_bytes)  // pledge <= budget
    throw ResourceExhausted(
        "memory_budget", "the request needs " + bytes_text(need) + " of device buffers, " +
                             bytes_text(p.reply_bytes) + " for its reply and " +
                             bytes_text(held_bytes) + " for its message: more than the server's " +
                             bytes_text(budget) + " memory budget (--memory-budget); ask for less");
  return p;
}

Plan plan_unlimited(const RenderRequest& request) {
  return make_plan(request);
}

SequencePrice price_sequence(const SequenceRequest& sequence, const PriceLimits& limits) {
  if (sequence.base.quality.goal != Quality::Goal::kNone)
    throw InvalidArgument("quality",
                          "is not available in sequences (each frame would pick its own map): "
                          "set shadow_map.technique and size");
  validate_frames(sequence);
  SequencePrice p;
  size_t dearest = 0;
  for (size_t i = 0; i < sequence.frames.size(); ++i) {
    const RenderRequest frame = frame_request(sequence, i);
    with_field_renamed(
        [&] {
          validate(frame, limits.validation);
          p.plans.push_back(make_plan(frame));
          const CostEstimate cost = estimate_cost(frame, p.plans.back());
          admit(cost, limits.max_request_ms, limits.budget_bytes);
          p.frame_ms.push_back(cost.ms);
          p.ms += cost.ms;
          if (cost.ms > p.frame_ms[dearest]) dearest = i;
          p.device_bytes = std::max(p.device_bytes, cost.device_bytes);
          p.reply_bytes = std::max(p.reply_bytes, output_bytes(frame));
        },
        [&](const std::string& field) { return frame_field(sequence, i, field); });
  }
  // The whole sequence, priced before any frame runs: frames one at a time would each pass the
  // per-request limit while the sequence held a workspace for an hour.
  const double max_ms = limits.max_sequence_ms;
  if (max_ms > 0 && p.ms > max_ms)
    throw ResourceExhausted(
        "max_sequence_cost",
        "the sequence's " + std::to_string(sequence.frames.size()) + " frames are estimated at " +
            ms_text(p.ms) + " of device time in all (the dearest, frame " +
            std::to_string(dearest) + ": " + ms_text(p.frame_ms[dearest]) +
            "), over the server's limit of " + ms_text(max_ms) +
            " for a sequence (--max-sequence-cost); send fewer frames per call, or lighter ones");
  return p;
}

CandidateCost candidate_cost(const Price& goal, const PriceLimits& limits) {
  return [goal_probe_ms = goal.probe_ms, probe_predicted = goal.probe_predicted, limits](
             const RenderRequest& c, const MapLoads& loads) -> std::optional<CandidatePrice> {
    try {
      validate(c, limits.validation);
      CandidatePrice out;
      out.plan = make_plan(c);
      CostEstimate e = estimate_cost(c, out.plan);
      e.ms += goal_probe_ms;
      admit(e, limits.max_request_ms, limits.budget_bytes);
      Plan to_run = out.plan;  // without what it takes from the probe
      std::erase_if(to_run.steps,
                    [&](const Step& step) { return taken_from_probe(c, out.plan, step.kind); });
      out.time = limits.calibration->predict_time(c, to_run, loads) += probe_predicted;
      return out;
    } catch (const InvalidArgument&) {
      return std::nullopt;
    } catch (const ResourceExhausted&) {
      return std::nullopt;
    }
  };
}

}  // namespace shadow
