// shadow-bench --calibration's second pass: what a max_error goal predicts for each of its
// candidates on every view, from a server that loads the freshly counted table. The table's
// error margins (engine/choose/calibration.hpp, ErrorMargin) compare these predictions with the
// sweep's measurements of the same configurations run on their own ("uniform 1024", ...).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "engine/choose/calibration.hpp"
#include "oracle/standard_scenes.hpp"
#include "wire/types.hpp"

namespace shadow::bench {

// The camera of a view as the bench renders it: `width` wide, 16:9.
Camera bench_camera(const scenes::View& view, int width);

// Each view's goal candidates (QualityPick::candidates) under `calibration`, keyed
// "scene/view"; point lights' views (no goal there) are left out. Throws what the client
// throws on a refusal.
std::map<std::string, std::vector<QualityCandidate>> goal_candidates(
    const Calibration& calibration, const std::vector<scenes::StandardScene>& scenes, int width);

}  // namespace shadow::bench
