// shadow-bench's "quality goals" section (issue 17): each goal's pick, its predicted error and
// device time beside the measured ones per view, and against the fixed variants that met the
// same goal on that view.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "case.hpp"
#include "frames.hpp"

namespace shadow::bench {

// A fixed hard-test variant ("uniform 1024", "psm 2048", "lispsm 4096", "auto 2048"): the
// configurations a goal's pick is judged against.
bool is_fixed_configuration(const std::string& variant);

// A configuration's variant name, "lispsm 1024": how fixed runs, picks and candidates are named.
std::string configuration_name(Technique technique, uint32_t size);

// The variant whose map is the quality goals' probe's (uniform kQualityProbeSize): its boundary
// share stands for the view's in the calibration, its passes for the probe's work in a goal's cost.
std::string probe_variant();

// The fixed run among `fixed` of `technique` at `size` (configuration_name), if the sweep has one.
const Case* fixed_run(const std::vector<const Case*>& fixed, Technique technique, uint32_t size);

// A case's device time without the bench's own texel-density pass (every case asks for that
// product to measure footprints; a goal's user would not).
double configuration_ms(const Case& c);

// A goal's cost, summed from the fixed variants among `fixed` (the view's) that did the same
// work, so that it carries no second sample of the machine's noise: configuration_ms of the
// configuration it picked but for the steps it took from its probe (Case::reused), plus the
// probe's map and hard test as "uniform 512" measured them, plus the goal's own passes that
// only the probe runs (its boundary count, depth range, samples and candidates' raster loads;
// left out without `measures`). Without those variants: its own configuration_ms.
double goal_cost_ms(const Case& goal, const std::vector<const Case*>& fixed, bool measures = true);

// A case's misclassified rate as a judgement reads it: its own (own_rate), or its mean over the
// view and the view's nudged frames (frames.hpp, frame_mean_rate).
using RateOf = std::function<double(const Case&)>;
double own_rate(const Case& c);

// The goal as it would have run had each candidate's error been known: every candidate's
// predicted error replaced by what its fixed run among `fixed` measured (`rate`), the pick made
// by the engine's rule (choose_candidate) on the same predicted times, with what it would take
// from the probe. The error prediction's ceiling. Nullopt for a case without candidates, or
// where the rule would pick a candidate whose raster load the goal did not measure: its time is
// a lower bound, so the replay cannot tell (QualityCandidate::raster_load_priced).
std::optional<Case> with_measured_errors(const Case& goal, const std::vector<const Case*>& fixed,
                                         const RateOf& rate = own_rate);

// `goal` as it would have run had it picked `technique` at `size`, with what such a pick takes
// from the probe (a pick of the probe's own map: its map and hard test).
Case as_picked(const Case& goal, Technique technique, uint32_t size);

// Each view's ("scene/view") fixed configurations among `cases` (is_fixed_configuration).
std::map<std::string, std::vector<const Case*>> fixed_by_view(const std::vector<Case>& cases);

// The cheapest of `fixed` (configuration_ms) whose `rate` meets error bound `bound`; null where
// none does. What a max_error goal's cost is compared with.
const Case* cheapest_meeting(double bound, const std::vector<const Case*>& fixed,
                             const RateOf& rate = own_rate);

// Issue 17's cost bound on a max_error goal that met its bound: a goal's cost (goal_cost_ms) is
// within it when at most kCostRatio times the configuration_ms of `cheapest` (cheapest_meeting).
inline constexpr double kCostRatio = 1.5;
bool within_cost(double goal_ms, const Case& cheapest);

// Writes the section (nothing when no goal ran): a row per goal and view, then per goal how
// often it met its bound, and for max_error how its device time compares with the cheapest
// fixed variant that met the bound on the same view; with `frames`, the error goals judged
// again by every case's mean over the view and its nudged frames.
void write_quality_section(const std::vector<Case>& cases, const std::vector<FrameError>& frames,
                           std::ostream& md);

}  // namespace shadow::bench
