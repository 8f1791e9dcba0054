// What admission knows of a request or a sequence before it waits: validated, planned, priced
// and held to the server's limits (ResourceExhausted naming the one it meets). The one place
// where requests are planned (make_plan): the engine's requests and sequences, a quality goal's
// probe and candidates, and the engine's own warm-up.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "engine/choose/calibration.hpp"
#include "engine/choose/quality_pick.hpp"
#include "engine/plan/plan.hpp"
#include "engine/plan/validate.hpp"

namespace shadow {

// The limits a price is held to (EngineOptions' and the device's).
struct PriceLimits {
  Limits validation;           // the reply's bytes and the device's buffer size
  double max_request_ms = 0;   // 0 = none
  double max_sequence_ms = 0;  // 0 = none
  uint64_t budget_bytes = 0;   // the memory budget
  const Calibration* calibration = nullptr;
};

// A request's share of the memory budget for `device_bytes` of estimated buffers: as its
// workspace will allocate them, with the runtime's headroom, within the budget.
uint64_t pledged_bytes(uint64_t device_bytes, uint64_t budget_bytes);

// A request's price: its plan, estimate, the device buffers it waits for (a goal's: its probe's,
// the least it needs) and, `with_reply`, its reply's bytes (a goal's largest candidate's).
// `held_bytes`: what the caller already holds of the budget for it (its message).
struct Price {
  Plan plan;
  double ms = 0;  // a goal's: its probe's
  std::string driver;
  uint64_t device_bytes = 0, reply_bytes = 0;
  double probe_ms = 0;  // a goal's probe, added to each candidate's
  PredictedTime probe_predicted;
};
Price price_request(const RenderRequest& request, const PriceLimits& limits, bool with_reply,
                    uint64_t held_bytes);

// A request with no limits but the device's buffer size (the engine's warm-up, which asks for
// every product): its plan.
Plan plan_unlimited(const RenderRequest& request);

// A sequence's: every frame's plan and estimate, their sum against max_sequence_ms, and the
// largest frame's buffers (what each frame waits for) and reply.
struct SequencePrice {
  std::vector<Plan> plans;
  std::vector<double> frame_ms;
  double ms = 0;
  uint64_t device_bytes = 0, reply_bytes = 0;
};
SequencePrice price_sequence(const SequenceRequest& sequence, const PriceLimits& limits);

// A quality goal's candidates priced as requests (pick_quality), each with its goal's probe
// added: nothing for one the server would refuse.
CandidateCost candidate_cost(const Price& goal, const PriceLimits& limits);

}  // namespace shadow
