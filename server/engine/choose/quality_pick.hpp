// A quality goal (RenderRequest::quality): which technique and map size a request gets, from the
// predicted error and device time of each candidate. Pure math (no OpenCL), deterministic.
//
// Candidates: uniform, LiSPSM (every light directional) and PSM, at kQualitySizes, each fitted
// as the run fits it (candidate_matrix: to the receivers' boxes in view and the probe's measured
// depth range; uniform fitted to the view even under MAP_FIT_SCENE, so optimistic there). The error
// of one is the worst light's mean, over the probe's samples of the camera view (the seen surface
// at a grid of pixels), of the calibration's misclassified rate at the sample's predicted texel
// footprint (which scales as 1 / size; samples off the map, on a side facing away from the light
// or not receiving count 0: nothing there can be misclassified), a rate per boundary pixel, times
// the light's boundary share: the share of the camera's seen pixels on a shadow edge of the probe
// that a map can misplace (engine/passes/boundary.hpp: not the geometry's), the hard test against
// a uniform kQualityProbeSize map fitted as the request's would be (quality_probe(),
// QualityProbe::probe; its passes are timed as "quality_probe.*"). The mean weighs each sample by
// the probe's boundary pixels in its grid cell: a map errs on the shadow edges, so the footprint
// there decides (a plain mean where the samples' cells hold none). Times the
// calibration's error margin for the technique and size (Calibration::error_margin: measured over
// predicted on the standard views at their 70th percentile, so a bound is met on most). The
// time is the caller's (the engine's: the calibration's typical rates, and those times its
// margin for the 90th percentile, the probe's included) with the candidate's raster load where
// the pick measured it (below), and a candidate the caller would refuse (admission) has none.
// max_error: the candidate predicted to meet it at the lowest typical time, else the most accurate;
// max_device_ms: the most accurate predicted (90th percentile) to fit, else the fastest. Ties go to
// the smaller map, then the simpler technique (uniform, LiSPSM, PSM).
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <vector>

#include "engine/choose/auto_pick.hpp"  // Sample
#include "engine/choose/calibration.hpp"
#include "engine/light/light_space.hpp"
#include "engine/plan/cost.hpp"  // MapLoads
#include "engine/plan/plan.hpp"
#include "wire/types.hpp"

namespace shadow {

inline constexpr std::array<uint32_t, 4> kQualitySizes = {512, 1024, 2048, 4096};  // doubling
// The probe's map edge: cheap next to the candidates, fine enough to show the view's shadow
// edges. shadow-bench calibrates against its "uniform 512" variant, the same map.
inline constexpr uint32_t kQualityProbeSize = 512;

// A candidate request's plan and its device time when its maps load the raster with `loads` (one
// per light; none where the probe did not predict them), or nullopt where the server would
// refuse it (engine/choose/price.hpp).
struct CandidatePrice {
  Plan plan;
  PredictedTime time;
};
using CandidateCost =
    std::function<std::optional<CandidatePrice>(const RenderRequest&, const MapLoads& loads)>;

// What the goal's probe measured (QualityProbe::probe).
struct ProbeMeasure {
  std::vector<double> boundary;  // each light's boundary share, in the request's order
  std::vector<Sample> samples;   // the camera view's seen grid pixels (passes/view_samples.hpp)
  // Per light (empty: none measured), per sample: the probe's boundary pixels in the sample's
  // grid cell (passes/boundary.hpp), which weigh the sample's predicted rate.
  std::vector<std::vector<double>> weights;
  // The camera view's receivers' depth range (passes/depth_range.hpp; none where none is seen
  // or not measured), which PSM's and LiSPSM's candidates are fitted to, as the run fits them.
  std::optional<DepthRange> depth;
};

// A candidate technique's maps' raster load, what the texel count misses of a warped map's
// raster time, measured on demand: `measure` sets up the technique's map of each light
// (Rasterizer::load of the casters through candidate_matrix) and returns, per kQualitySizes,
// the loads per light; `each` is what one such measure is predicted to cost.
struct CandidateLoads {
  std::function<std::array<MapLoads, kQualitySizes.size()>(Technique)> measure;
  PredictedTime each;
};

// The techniques a goal weighs for the request: uniform; LiSPSM (every light directional) and
// PSM unless the filter needs uniform maps.
std::vector<Technique> quality_techniques(const RenderRequest& request);

// Light `light`'s map matrix for a candidate of `technique`, fitted as the run fits it: to the
// receivers' boxes in view and, for PSM and LiSPSM, the view's measured `depth` range.
glm::dmat4 candidate_matrix(const RenderRequest& request, size_t light, Technique technique,
                            const std::vector<InstanceBounds>& instances,
                            const std::optional<DepthRange>& depth);

// For a validated request with a goal and no point light; `instances` fit the candidates' maps.
// The pick carries every candidate the caller would admit. Throws ResourceExhausted("quality")
// when the caller refuses every candidate.
// Raster loads are measured only where they decide the pick: the candidates are weighed without
// them first (a lower bound of their time), then the chosen one's technique is measured and its
// candidates priced with their loads, and the choice made again, until the chosen one is priced
// (at most once per technique; a candidate drawing the probe's map draws none). Each measure
// taken adds `loads.each` to every candidate's time. Without `loads.measure`, none is priced.
QualityPick pick_quality(const RenderRequest& request, const std::vector<InstanceBounds>& instances,
                         const ProbeMeasure& probe, const Calibration& calibration,
                         const CandidateCost& cost, const CandidateLoads& loads = {});

// Whether a candidate's prediction meets the goal (max_error: its error, max_device_ms: its time).
bool meets_goal(const QualityCandidate& candidate, const Quality& goal);

// The rule alone: which of `candidates` (non-empty, in pick_quality's order) a goal picks.
const QualityCandidate& choose_candidate(const std::vector<QualityCandidate>& candidates,
                                         const Quality& goal);

// The goal's probe as a request of its own: the hard test of the request's camera and lights
// against uniform kQualityProbeSize maps, visibility only, no goal. QualityProbe::probe
// runs it; the engine admits it before any candidate and adds its estimate to each candidate's.
RenderRequest quality_probe(const RenderRequest& request);

// Whether a picked request's step of `kind` is taken from the goal's probe instead of run: its
// maps when they are the probe's (uniform kQualityProbeSize, no blur classes, which the probe
// does not draw), and with one light and the hard filter its hard test too. The workspace also
// checks that the maps' matrices are the probe's (QualityProbe::take_map).
bool taken_from_probe(const RenderRequest& picked, const Plan& plan, StepKind kind);

// The request as the pick makes it: the technique and size set, the goal gone.
RenderRequest with_pick(const RenderRequest& request, const QualityPick& pick);

}  // namespace shadow
