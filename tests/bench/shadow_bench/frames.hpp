// shadow-bench's nudged frames: variants run again with the light turned a twentieth of a
// degree, four ways (the bench runs those compared with AUTO, the fixed configurations and the
// error goals). A hard test's misclassified rate is deterministic, but it hangs on where the
// shadow edges fall on the map's texel grid: on the street seen from eye height, uniform 2048
// misclassified 0.53% of the pixels and 1.28% with the sun turned 0.05°, while the warped maps
// moved by 0.03 points. The spread over such frames is the noise that a comparison of
// techniques on one view has to beat (issue 17's goals), and their mean is what a sequence of
// frames would see.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "case.hpp"
#include "oracle/metrics.hpp"
#include "wire/types.hpp"

namespace shadow::bench {

// How far a nudged frame turns the light (a directional light's travel, a spot's axis), and
// how far it moves a point light.
inline constexpr double kNudgeDeg = 0.05;
inline constexpr double kNudgeM = 0.01;

// The four nudged lights: turned by kNudgeDeg sideways both ways, then up and down (directional
// and spot lights; a spot keeps its position), or moved by +-kNudgeM along x, then z (point
// lights).
std::vector<Light> nudged_lights(const Light& light);

// One variant's misclassified rates on one nudged frame (1-4; frame 0 is the view's own Case).
struct FrameError {
  std::string scene, view, variant;
  int frame = 0;
  Light light;
  oracle::VisibilityError error;
  std::vector<oracle::DistanceBand> bands;
};

// Renders `variants` on every nudged light of one view, each once, and scores it against that
// light's hard reference (`reference`), near and far by `distance` as the bench's cases are.
// `render` returns the visibility, or nothing where the server refused the variant.
using RenderVisibility = std::function<std::optional<std::vector<float>>(const std::string& variant,
                                                                         const Light& light)>;
std::vector<FrameError> run_nudged_frames(
    const std::string& scene, const std::string& view, const Light& light,
    const std::vector<std::string>& variants, const RenderVisibility& render,
    const std::function<std::vector<float>(const Light&)>& reference,
    const std::vector<double>& distance);

// A case's mean misclassified rate over its view (frame 0, the case's own) and the nudged frames
// of the same scene, view and variant among `frames` (indexed once).
std::function<double(const Case&)> frame_mean_rate(const std::vector<FrameError>& frames);

}  // namespace shadow::bench
