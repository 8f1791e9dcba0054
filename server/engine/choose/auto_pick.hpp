// TECHNIQUE_AUTO: which parameterization a request gets, decided from the light, the camera and
// the receivers before any map is drawn. Pure math (no OpenCL), deterministic.
//
// A point light gets its cube (no single map covers every direction). Otherwise each candidate
// (uniform, LiSPSM for a directional light, PSM, and PSM's cube where the request allows cube
// faces (plan.hpp, auto_may_cube) and its light needs more than one; uniform alone with PCSS and
// PCSS-CSM, which need an ordinary projection) is fitted as the engine would fit it, and its texel
// footprint predicted at a grid of camera pixels: on the camera view's surface when the request
// draws it (passes/view_samples.hpp), else where the pixels' rays hit the receivers' boxes. A
// footprint is the size in pixels of one map texel on the surface there, as PRODUCT_TEXEL_DENSITY
// measures it per pixel (the larger singular value of J_camera * inverse(J_light) on the tangent
// plane). The cube is drawn at equal texels: each rendered face at psm_cube_face_size.
// The server scores each by its predicted misclassified pixels per shadow-boundary pixel
// (engine/choose/calibration.hpp: the calibration's rate at each sample's footprint, samples off
// the map or on the view's sides facing away from the light counting 0; the view's boundary share,
// which a quality goal's probe measures, is the same for every candidate, so AUTO draws no probe)
// and keeps the simpler one (uniform, then LiSPSM, PSM, PSM's cube) within kErrorTie (relative) of
// the best. Without a calibration the score is the share of under-sampled samples (texel > 1 px,
// TEXEL_DENSITY's fraction_above_1; samples outside a map left out), the tie kTie. Where the
// request draws the camera view, the candidates the score leaves close are then tried on it
// (trial_candidates, below; LightFitter::try_candidates). Measured on the 22 standard views
// against the best of uniform, PSM, LiSPSM and PSM_CUBE at ~4.2 M texels: docs/benchmarks.md,
// "TECHNIQUE_AUTO".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "engine/light/light_space.hpp"
#include "engine/light/psm_fit.hpp"   // DepthRange
#include "engine/plan/technique.hpp"  // technique_label
#include "wire/types.hpp"

namespace shadow {

inline constexpr double kFootprintCap = 64.0;  // px: a grazing texel's mean term, not inf
inline constexpr double kTie = 0.01;           // under-sampled shares this close are a tie

struct AutoCandidate {
  Technique technique;
  uint32_t size = 0;          // its maps' edge: the request's, or each PSM_CUBE face's
  double undersampled = 0;    // share of the samples with texel > 1 px: the score
  double mean_footprint = 0;  // px (each capped at kFootprintCap), reported
  size_t samples = 0;         // camera-ray samples inside the map
  int faces = 1;              // maps rendered (PSM_CUBE's faces)
  // With a calibration: the predicted misclassified pixels per boundary pixel (the score).
  double predicted_error = NAN;
  // Tried (choose_by_trial): its maps' edge in the trial, and the mean over the camera's seen
  // pixels of |hard - bilinear 2x2| against those maps (the misclassified share edge sampling
  // explains, passes/edge_sampling.hpp); else 0 and NaN.
  uint32_t trial_size = 0;
  double trial_edge = NAN;
};

inline constexpr const char* kPicked = "picked ";  // how every AutoPick::reason starts

struct AutoPick {
  Technique technique = Technique::kUniform;
  uint32_t size = 0;  // the edge of its maps: the request's size, each face's for PSM_CUBE
  // "picked lispsm: predicted texel > 1 px at 13.2% of 266 samples (mean footprint 3.1 px);
  // uniform 60.5% (9.6 px), psm 59.2% (9.4 px)"; after a trial, what the trial measured, then
  // whether the prediction agreed or what it alone picked.
  std::string reason;
  std::vector<AutoCandidate> candidates;  // in the order considered
};

// The texel footprint (px) of a map at surface point p with normal n, as kernels/texel_density.cl
// computes it; NaN outside the map, +inf where the light grazes the surface.
double texel_footprint(const glm::dmat4& light_to_ndc, uint32_t map_size,
                       const glm::dmat4& camera_to_ndc, uint32_t width, uint32_t height,
                       const glm::dvec3& p, const glm::dvec3& n);

// A point of a receiver seen by the camera and its normal (towards the eye).
struct Sample {
  glm::dvec3 p, n;
};
// The camera's sample grid: the centres of kSampleColumns x kSampleRows equal cells.
inline constexpr uint32_t kSampleColumns = 24, kSampleRows = 14;

// Where the grid's pixel rays first meet an instance's box, if that instance receives shadows:
// the point and the box face's normal.
std::vector<Sample> receiver_samples(const Camera& camera,
                                     const std::vector<InstanceBounds>& instances);

// Whether a sample's side faces the light (n . l > 0). A side facing away or edge-on is an
// attached shadow, dark under every map (kernels/pcf.cl), so no map can misclassify it: its
// predicted error is 0, and the calibration leaves such pixels out.
bool faces_light(const Light& light, const Sample& s);

// The world -> map NDC matrix a light gets with `technique` (uniform, LiSPSM or PSM, default
// settings), fitted as the engine fits it.
glm::dmat4 fitted_matrix(Technique technique, const Light& light, const Camera& camera,
                         const std::vector<InstanceBounds>& instances,
                         const std::optional<DepthRange>& measured);

// The edge of each of `faces` cube faces holding about the texels of one map_size^2 map: the
// largest multiple of 16 with faces * edge^2 <= map_size^2 (912 for 5 faces at 2048).
uint32_t psm_cube_face_size(uint32_t map_size, int faces);

// With `calibration`, candidates are scored by their predicted error per boundary pixel (as quality
// goals predict it before scaling by the boundary share: the calibration's rate at each sample's
// footprint, samples off the map counting 0), the simpler within kErrorTie of the best (relative);
// without, by the under-sampled share. The samples are the camera view's (`view`,
// passes/view_samples.hpp) when the request draws it: the seen surface, where a side facing away
// from the light predicts no error (faces_light). Without, the receivers' boxes (receiver_samples):
// a box face's normal does not say which side of what it holds faces the light, so none counts 0
// for it. `psm_cube_guard`: PSM's cube is a candidate, its faces with this guard band
// (cube_fit.hpp, filter_reach), when the request allows cube faces (plan.hpp, auto_may_cube).
// Predicted errors within this share of the smaller are a tie. Relative: AUTO draws no probe, so
// it does not know the view's boundary share, which scales every candidate's error alike (an
// absolute 0.02 per boundary pixel was 0.6% of the pixels on the forest seen from above, where
// LiSPSM, predicted 12% better, measured 32% better than uniform).
inline constexpr double kErrorTie = 0.1;
AutoPick pick_technique(const Light& light, const Camera& camera,
                        const std::vector<InstanceBounds>& instances, uint32_t map_size,
                        FilterKind filter, const std::optional<DepthRange>& measured,
                        const class Calibration* calibration = nullptr,
                        const std::vector<Sample>* view = nullptr,
                        std::optional<uint32_t> psm_cube_guard = std::nullopt);

// The trial (where the request draws the camera view): the footprint prediction ranks
// techniques well where they differ by much, but not where they are close or where a map's
// error is not the receivers' footprint (the forest's trees, grazing receivers). On the sweep
// after the reference's ray-offset fix (2026-11-26), 19 views with a directional or spot light, the
// best fixed technique at equal texels was the predicted best on 10, and predicted at most 6x the
// best's error on all (uniform on the street with the light behind the camera; 10.9x on the
// edge-weighted table of 2026-11-26, whose rates per boundary pixel are counted where the edges lie
// and grow faster with the footprint, which AUTO averages over the whole view). So each candidate
// predicted within kTrialRatio of the best is drawn at half its edge (trial_size) and the camera
// view tested against it hard and bilinear 2x2 (in one pass); the least mean |hard - bilinear|
// wins, the simpler within kTrialTie of it (relative). The ratio leaves out the hopeless (PSM at
// 41-70x on the street); at 2 the sweep lost the street's uniform pick, and at 8 on the
// edge-weighted table (docs/decisions/2026-11-26-footprint-where-the-edges-are.md).
// docs/benchmarks.md, "AUTO's trial", has what it picks and costs.
inline constexpr double kTrialRatio = 16.0;
inline constexpr double kTrialTie = 0.05;

// The candidates to try, in order: with a calibration those predicted within kTrialRatio of the
// best, without one all; none when fewer than two.
std::vector<size_t> trial_candidates(const AutoPick& pick);

// The edge of a candidate's maps in the trial: half its edge, a multiple of 16, at least
// kMinMapSize and at most its own edge.
uint32_t trial_size(uint32_t size);

// What a light's trial measured in a sequence (Workspace keeps one per light): the candidates
// tried, with their predictions then and their trial figures, the pick, and the frame.
struct TrialVerdict {
  std::vector<AutoCandidate> tried;
  Technique picked = Technique::kUniform;
  uint64_t frame = 0;
};

// A sequence's frames keep their light's last trial while the prediction that framed it holds:
// the same candidates to try, each predicted within kVerdictDrift (relative) of its prediction
// then, and the trial at most kVerdictFrames frames old. Two reasons: the trial is about half of
// AUTO's device time (docs/benchmarks.md), and a pick that changes between close frames makes the
// shot's shadow edges jump. When the trial runs again, the last pick stays within kTrialTie of the
// least, for the same reason.
inline constexpr double kVerdictDrift = 0.25;
inline constexpr uint64_t kVerdictFrames = 24;
bool verdict_holds(const AutoPick& pick, const std::vector<size_t>& tried,
                   const TrialVerdict& verdict, uint64_t frame);

// Picks among the candidates `tried` (indices into pick.candidates, from trial_candidates), each
// measured `edge` (the mean |hard - bilinear|) at `sizes`: `kept` (the sequence's last pick) if
// within kTrialTie (relative) of the least, else the earliest (simpler) within it. Sets the pick's
// technique, size and reason ("lispsm: least edge sampling in the trial ...; predicted: <the
// footprint prediction's reason>"); `from_frame`: the figures are that frame's trial, kept.
void choose_by_trial(AutoPick& pick, const std::vector<size_t>& tried,
                     const std::vector<double>& edge, const std::vector<uint32_t>& sizes,
                     std::optional<Technique> kept = std::nullopt,
                     std::optional<uint64_t> from_frame = std::nullopt);

}  // namespace shadow
