// TECHNIQUE_AUTO's pick as pure math (issue 17), without OpenCL: a table of light and camera
// cases with the pick each must get and why, the same pick every time, the pick the smallest
// predicted under-sampled share (or the simpler candidate within kTie of it), and the predicted
// footprint against a finite-difference measure of one texel's size in pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/choose/auto_pick.hpp"
#include "engine/choose/calibration.hpp"

namespace shadow {
namespace {

const std::vector<InstanceBounds>& street() {
  static const std::vector<InstanceBounds> s = [] {
    std::vector<InstanceBounds> v = {{Bounds{{-40, -1, -300}, {40, 0, 10}}, true, true}};
    for (int k = 0; k < 12; ++k)  // houses along both sides
      for (double x : {-14.0, 8.0})
        v.push_back({Bounds{{x, 0, -20.0 * k - 12}, {x + 6, 9, -20.0 * k - 4}}, true, true});
    return v;
  }();
  return s;
}

Camera walker() {
  Camera c;
  c.eye = {0, 1.7f, 0};
  c.target = {0, 1.2f, -20};
  c.width = 320, c.height = 180;
  c.near = 0.1f, c.far = 300;
  return c;
}

Camera top_down() {
  Camera c;
  c.eye = {0, 120, -100};
  c.target = {0, 0, -100};
  c.up = {0, 0, -1};
  c.width = 320, c.height = 180;
  c.near = 1, c.far = 300;
  return c;
}

Light sun(glm::vec3 direction) {
  Light l;
  l.direction = direction;
  return l;
}

const AutoCandidate& of(const AutoPick& p, Technique t) {
  for (const AutoCandidate& c : p.candidates)
    if (c.technique == t) return c;
  throw std::runtime_error("no such candidate");
}

struct Row {
  const char* name;
  Light light;
  Camera camera;
  FilterKind filter;
  Technique expected;
  const char* why;
};

TEST(AutoPick, TableOfLightAndCameraCases) {
  Light point;
  point.type = LightType::kPoint;
  point.position = {0, 5, -30};
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0, 30, 0};
  spot.direction = {0, -1, -1};
  spot.cone_angle_deg = 70;
  const DepthRange range{1.7, 300};
  const Row rows[] = {
      {"point light", point, walker(), FilterKind::kHard, Technique::kCube,
       "no single map covers every direction"},
      {"pcss", sun({1, -1, 0.2f}), walker(), FilterKind::kPcss, Technique::kUniform,
       "PCSS needs an ordinary projection"},
      {"walker, sun from the side", sun({1, -0.7f, 0}), walker(), FilterKind::kHard,
       Technique::kLispsm,
       "the near street needs the warp (measured under-sampled: uniform 88.0%, lispsm 15.0%, psm "
       "14.3%: psm is within 1%, so the simpler lispsm)"},
      // Measured: no sample under-sampled by any (mean footprint uniform 0.18 px, the others
      // 0.089 px).
      {"top-down, sun overhead", sun({0, -1, 0}), top_down(), FilterKind::kHard,
       Technique::kUniform, "every map resolves every sample: nothing to gain, the simplest"},
  };
  for (const Row& r : rows) {
    const AutoPick a = pick_technique(r.light, r.camera, street(), 2048, r.filter, range);
    const AutoPick b = pick_technique(r.light, r.camera, street(), 2048, r.filter, range);
    std::printf("[ auto     ] %-26s -> %s\n", r.name, a.reason.c_str());
    EXPECT_EQ(a.technique, r.expected) << r.name << " (" << r.why << "): " << a.reason;
    EXPECT_EQ(b.technique, a.technique) << r.name;
    EXPECT_EQ(b.reason, a.reason) << r.name;
    if (a.candidates.empty()) continue;
    double best = INFINITY;
    for (const AutoCandidate& c : a.candidates) best = std::min(best, c.undersampled);
    EXPECT_LE(of(a, a.technique).undersampled, best + kTie) << r.name;
    // Only an earlier (simpler) candidate may be within the tie and not picked.
    for (const AutoCandidate& c : a.candidates) {
      if (c.technique == a.technique) break;
      EXPECT_GT(c.undersampled, best + kTie) << r.name;
    }
    for (const AutoCandidate& c : a.candidates) EXPECT_GT(c.samples, 50u) << r.name;
  }
  // A spot light: uniform or PSM only (no LiSPSM), each predicted.
  const AutoPick s = pick_technique(spot, walker(), street(), 2048, FilterKind::kHard, range);
  std::printf("[ auto     ] %-26s -> %s\n", "spot", s.reason.c_str());
  ASSERT_EQ(s.candidates.size(), 2u);
  EXPECT_EQ(s.candidates[0].technique, Technique::kUniform);
  EXPECT_EQ(s.candidates[1].technique, Technique::kPsm);
  EXPECT_EQ(s.technique, Technique::kPsm) << s.reason;  // measured: uniform 28.1%, psm 0%
}

// The predicted footprint is one texel's size in pixels: step one texel across the map on a
// plane seen straight on and measure the step in camera pixels by projecting both points.
TEST(AutoPick, FootprintIsOneTexelInPixels) {
  const Camera cam = top_down();
  const glm::dmat4 camera_m = camera_setup(cam).world_to_ndc;
  // An orthographic light straight down over a 100 m square (its view's y is the world's -z):
  // a texel is 100/1024 m.
  const glm::dmat4 light_m =
      gl_to_texture_ndc() * glm::ortho(-50.0, 50.0, 50.0, 150.0, 1.0, 500.0) *
      glm::lookAt(glm::dvec3(0, 200, 0), glm::dvec3(0, 0, 0), glm::dvec3(0, 0, -1));
  const glm::dvec3 p(3, 0, -97), n(0, 1, 0);
  const double f = texel_footprint(light_m, 1024, camera_m, cam.width, cam.height, p, n);
  auto pixel = [&](const glm::dvec3& q) {
    const glm::dvec4 c = camera_m * glm::dvec4(q, 1.0);
    return glm::dvec2(c.x / c.w * cam.width, c.y / c.w * cam.height);
  };
  const double texel = 100.0 / 1024;
  const double measured = std::max(glm::length(pixel(p + glm::dvec3(texel, 0, 0)) - pixel(p)),
                                   glm::length(pixel(p + glm::dvec3(0, 0, texel)) - pixel(p)));
  EXPECT_NEAR(f, measured, 1e-6 * measured);
  EXPECT_TRUE(
      std::isnan(texel_footprint(light_m, 1024, camera_m, cam.width, cam.height, {80, 0, -97}, n)));
}

// With the camera view's samples the calibrated score reads them, and a side facing away from
// the light predicts no error there; the receivers' boxes (no view) count every sample.
TEST(AutoPick, TheViewsSamplesFacingAwayFromTheLightPredictNoError) {
  const Light light = sun({1, -0.7f, 0});
  const Camera camera = walker();
  const Calibration& calibration = Calibration::built_in();
  std::vector<Sample> seen = receiver_samples(camera, street());
  const AutoPick boxes =
      pick_technique(light, camera, street(), 2048, FilterKind::kHard, std::nullopt, &calibration);
  const AutoPick same = pick_technique(light, camera, street(), 2048, FilterKind::kHard,
                                       std::nullopt, &calibration, &seen);
  ASSERT_EQ(boxes.candidates.size(), same.candidates.size());
  for (size_t i = 0; i < boxes.candidates.size(); ++i) {
    // The same points: only those facing away from the light drop out.
    EXPECT_LE(same.candidates[i].predicted_error, boxes.candidates[i].predicted_error);
    EXPECT_GT(same.candidates[i].predicted_error, 0.0);
  }
  for (Sample& s : seen) s.n = glm::normalize(glm::dvec3(light.direction));  // all facing away
  const AutoPick away = pick_technique(light, camera, street(), 2048, FilterKind::kHard,
                                       std::nullopt, &calibration, &seen);
  for (const AutoCandidate& c : away.candidates) EXPECT_EQ(c.predicted_error, 0.0);
  EXPECT_EQ(away.technique, Technique::kUniform);  // all tie: the simplest
}

// The cube's faces hold about one map's texels: the largest multiple of 16 that fits.
TEST(AutoPick, CubeFacesHoldOneMapsTexels) {
  EXPECT_EQ(psm_cube_face_size(2048, 5), 912u);  // shadow-bench's equal-texel cube
  EXPECT_EQ(psm_cube_face_size(2048, 4), 1024u);
  EXPECT_EQ(psm_cube_face_size(2048, 1), 2048u);
  EXPECT_EQ(psm_cube_face_size(2048, 0), 0u);
  for (uint32_t size : {256u, 640u, 1000u, 2048u, 4096u, 8192u})
    for (int faces = 1; faces <= 6; ++faces) {
      const uint64_t e = psm_cube_face_size(size, faces), s = size;
      EXPECT_EQ(e % 16, 0u);
      EXPECT_LE(faces * e * e, s * s) << size << " " << faces;
      EXPECT_GT(faces * (e + 16) * (e + 16), s * s) << size << " " << faces;
    }
}

// With a guard band (the request allows cube faces) PSM's cube is a candidate wherever the PSM
// fit is a cube: its faces at equal texels, scored like the others (the calibration's
// psm_cube rates), last in the order so that a tie keeps a single map. Not at 256, whose faces
// would be under the smallest map.
TEST(AutoPick, PsmsCubeIsACandidateWhereTheLightNeedsOne) {
  const Camera camera = walker();
  const DepthRange range{1.7, 300};
  const Calibration& calibration = Calibration::built_in();
  int cubes = 0;
  for (glm::vec3 d : {glm::vec3(1, -0.7f, 0), glm::vec3(0.3f, -0.5f, 1), glm::vec3(0.2f, -0.3f, -1),
                      glm::vec3(0.5f, -0.1f, 1)}) {
    const Light light = sun(glm::normalize(d));
    const AutoPick with = pick_technique(light, camera, street(), 2048, FilterKind::kHard, range,
                                         &calibration, nullptr, 1u);
    const AutoPick without =
        pick_technique(light, camera, street(), 2048, FilterKind::kHard, range, &calibration);
    const AutoPick small = pick_technique(light, camera, street(), 256, FilterKind::kHard, range,
                                          &calibration, nullptr, 1u);
    std::printf("[ auto     ] sun (%.1f, %.1f, %.1f): %s\n", d.x, d.y, d.z, with.reason.c_str());
    EXPECT_EQ(without.candidates.size(), 3u);
    EXPECT_EQ(small.candidates.size(), 3u);
    for (const AutoCandidate& c : without.candidates) EXPECT_NE(c.technique, Technique::kPsmCube);
    if (with.candidates.size() == 3) {
      EXPECT_EQ(with.technique, without.technique);  // the same candidates, the same pick
      continue;
    }
    ++cubes;
    ASSERT_EQ(with.candidates.size(), 4u);
    const AutoCandidate& cube = with.candidates.back();
    EXPECT_EQ(cube.technique, Technique::kPsmCube);
    EXPECT_GE(cube.faces, 1);
    EXPECT_LE(cube.faces, 6);
    EXPECT_EQ(cube.size, psm_cube_face_size(2048, cube.faces));
    EXPECT_GT(cube.predicted_error, 0.0);
    EXPECT_NE(with.reason.find("psm_cube (" + std::to_string(cube.faces) + " faces of " +
                               std::to_string(cube.size) + "^2)"),
              std::string::npos)
        << with.reason;
    EXPECT_EQ(with.size, with.technique == Technique::kPsmCube ? cube.size : 2048u);
  }
  EXPECT_GE(cubes, 1);  // the light facing the camera puts it at a point in post-perspective space
}

}  // namespace
}  // namespace shadow

namespace shadow {
namespace {

AutoCandidate candidate(Technique t, uint32_t size, double predicted, int faces = 1) {
  AutoCandidate c{t, size};
  c.predicted_error = predicted;
  c.faces = faces;
  return c;
}

// The trial draws those predicted within kTrialRatio of the best, and none when one is left.
TEST(AutoTrial, TriesTheCandidatesPredictedWithinTheRatio) {
  AutoPick pick;
  pick.candidates = {candidate(Technique::kUniform, 2048, 0.169),
                     candidate(Technique::kLispsm, 2048, 0.068),
                     candidate(Technique::kPsm, 2048, 0.055),
                     candidate(Technique::kPsmCube, 1024, 0.041, 4)};  // the forest walker's
  EXPECT_EQ(trial_candidates(pick), (std::vector<size_t>{0, 1, 2, 3}));
  pick.candidates[0].predicted_error = 0.6561;  // just over 16 x 0.041
  EXPECT_EQ(trial_candidates(pick), (std::vector<size_t>{1, 2, 3}));
  pick.candidates[0].predicted_error = 0.656;  // 16 x 0.041: tried
  EXPECT_EQ(trial_candidates(pick), (std::vector<size_t>{0, 1, 2, 3}));
  pick.candidates[0].predicted_error = pick.candidates[1].predicted_error =
      pick.candidates[2].predicted_error = 0.66;
  EXPECT_TRUE(trial_candidates(pick).empty());  // the prediction alone decides
  // Without a calibration (NaN predictions) every candidate is tried.
  for (AutoCandidate& c : pick.candidates) c.predicted_error = NAN;
  EXPECT_EQ(trial_candidates(pick), (std::vector<size_t>{0, 1, 2, 3}));
}

TEST(AutoTrial, DrawsHalfTheEdge) {
  EXPECT_EQ(trial_size(2048), 1024u);
  EXPECT_EQ(trial_size(912), 448u);  // a multiple of 16
  EXPECT_EQ(trial_size(1168), 576u);
  EXPECT_EQ(trial_size(512), 256u);
  EXPECT_EQ(trial_size(300), 256u);  // never under the smallest map
  EXPECT_EQ(trial_size(256), 256u);
}

// The least measured wins, the simpler (earlier) within kTrialTie of it; the reason names the
// trial's figures and keeps the prediction's.
TEST(AutoTrial, PicksTheLeastMeasuredTheSimplerWithinTheTie) {
  AutoPick base;
  base.candidates = {candidate(Technique::kUniform, 2048, 0.048),
                     candidate(Technique::kLispsm, 2048, 0.029),
                     candidate(Technique::kPsm, 2048, 0.034),
                     candidate(Technique::kPsmCube, 1168, 0.025, 3)};  // the forest overview's
  base.technique = Technique::kPsmCube;
  base.size = 1168;
  base.reason = "picked psm_cube (3 faces of 1168^2): predicted 0.025";
  const std::vector<size_t> all = {0, 1, 2, 3};
  const std::vector<uint32_t> sizes = {1024, 1024, 1024, 576};

  AutoPick pick = base;
  choose_by_trial(pick, all, {0.0090, 0.0069, 0.0120, 0.0101}, sizes);
  EXPECT_EQ(pick.technique, Technique::kLispsm);
  EXPECT_EQ(pick.size, 2048u);
  EXPECT_EQ(pick.candidates[3].trial_size, 576u);
  EXPECT_EQ(pick.candidates[3].trial_edge, 0.0101);
  EXPECT_EQ(pick.reason,
            "picked lispsm: least edge sampling in the trial, 0.00690 of the seen pixels "
            "(lispsm 1024^2), uniform 1024^2 0.00900, psm 1024^2 0.01200, psm_cube 3 x 576^2 "
            "0.01010; the prediction alone picked psm_cube (3 faces of 1168^2): predicted 0.025");

  pick = base;  // uniform within 5% of the cube: the simpler
  choose_by_trial(pick, all, {0.0104, 0.0110, 0.0120, 0.0100}, sizes);
  EXPECT_EQ(pick.technique, Technique::kUniform);
  pick = base;  // 6% is not a tie
  choose_by_trial(pick, all, {0.0106, 0.0110, 0.0120, 0.0100}, sizes);
  EXPECT_EQ(pick.technique, Technique::kPsmCube);
  EXPECT_EQ(pick.size, 1168u);

  pick = base;  // only the cube and PSM tried: the others keep no trial figures
  choose_by_trial(pick, {2, 3}, {0.0050, 0.0100}, {1024, 576});
  EXPECT_EQ(pick.technique, Technique::kPsm);
  EXPECT_TRUE(std::isnan(pick.candidates[0].trial_edge));
  EXPECT_EQ(pick.candidates[0].trial_size, 0u);
  EXPECT_THROW(choose_by_trial(pick, {2, 3}, {0.005}, {1024}), std::logic_error);
}

// A sequence keeps its last pick within the tie, even where a simpler candidate is also within
// it; outside the tie the least wins as ever. A kept trial's reason names its frame.
TEST(AutoTrial, ASequencesLastPickWinsTies) {
  AutoPick base;
  base.candidates = {candidate(Technique::kUniform, 2048, 0.048),
                     candidate(Technique::kLispsm, 2048, 0.029),
                     candidate(Technique::kPsm, 2048, 0.034)};
  base.reason = "lispsm: predicted 0.029";
  const std::vector<size_t> all = {0, 1, 2};
  const std::vector<uint32_t> sizes = {1024, 1024, 1024};
  AutoPick pick = base;  // all three within 5% of the least: the last pick, PSM, stays
  choose_by_trial(pick, all, {0.0101, 0.0102, 0.0100}, sizes, Technique::kPsm);
  EXPECT_EQ(pick.technique, Technique::kPsm);
  pick = base;  // without a last pick: the simplest of them
  choose_by_trial(pick, all, {0.0101, 0.0102, 0.0100}, sizes);
  EXPECT_EQ(pick.technique, Technique::kUniform);
  pick = base;  // the last pick 6% off the least: the least's tie decides
  choose_by_trial(pick, all, {0.0101, 0.0100, 0.0106}, sizes, Technique::kPsm);
  EXPECT_EQ(pick.technique, Technique::kUniform);
  pick = base;
  choose_by_trial(pick, all, {0.0120, 0.0100, 0.0130}, sizes, Technique::kLispsm, 7);
  EXPECT_EQ(pick.technique, Technique::kLispsm);
  EXPECT_EQ(
      pick.reason.rfind("picked lispsm: least edge sampling in frame 7's trial (kept), 0.01000", 0),
      0u)
      << pick.reason;
  pick = base;  // the trial agrees with the prediction, and says so
  pick.technique = Technique::kLispsm;
  pick.reason = "picked lispsm: predicted 0.029";
  choose_by_trial(pick, all, {0.0120, 0.0100, 0.0130}, sizes);
  EXPECT_EQ(pick.technique, Technique::kLispsm);
  EXPECT_NE(pick.reason.find("; the prediction agreed: lispsm: predicted 0.029"), std::string::npos)
      << pick.reason;
}

// A trial's verdict holds while the same candidates are tried, each predicted within
// kVerdictDrift of its prediction then, for at most kVerdictFrames frames.
TEST(AutoTrial, AVerdictHoldsWhileItsPredictionDoes) {
  AutoPick pick;
  pick.candidates = {candidate(Technique::kUniform, 2048, 0.048),
                     candidate(Technique::kLispsm, 2048, 0.029),
                     candidate(Technique::kPsm, 2048, 0.034),
                     candidate(Technique::kPsmCube, 1168, 0.500, 3)};  // not tried
  const std::vector<size_t> tried = trial_candidates(pick);
  ASSERT_EQ(tried, (std::vector<size_t>{0, 1, 2}));
  TrialVerdict verdict;
  for (size_t i : tried) verdict.tried.push_back(pick.candidates[i]);
  verdict.frame = 10;
  EXPECT_TRUE(verdict_holds(pick, tried, verdict, 10));
  EXPECT_TRUE(verdict_holds(pick, tried, verdict, 10 + kVerdictFrames));
  EXPECT_FALSE(verdict_holds(pick, tried, verdict, 11 + kVerdictFrames));  // too old
  EXPECT_FALSE(verdict_holds(pick, tried, verdict, 9));  // from another sequence's future
  AutoPick moved = pick;
  moved.candidates[1].predicted_error = 0.029 * 1.3;  // 23% of the larger: holds
  EXPECT_TRUE(verdict_holds(moved, tried, verdict, 12));
  moved.candidates[1].predicted_error = 0.029 * 1.4;  // 29%: the trial runs again
  EXPECT_FALSE(verdict_holds(moved, tried, verdict, 12));
  moved = pick;
  moved.candidates[2].size = 1024;
  EXPECT_FALSE(verdict_holds(moved, tried, verdict, 12));  // another candidate
  EXPECT_FALSE(verdict_holds(pick, {0, 1}, verdict, 12));  // fewer tried
  // Without a calibration, the under-sampled shares are the prediction.
  AutoPick plain = pick;
  for (AutoCandidate& c : plain.candidates) c.predicted_error = NAN, c.undersampled = 0.4;
  TrialVerdict uncalibrated;
  for (size_t i : tried) uncalibrated.tried.push_back(plain.candidates[i]);
  EXPECT_TRUE(verdict_holds(plain, tried, uncalibrated, 3));
  plain.candidates[0].undersampled = 0.2;
  EXPECT_FALSE(verdict_holds(plain, tried, uncalibrated, 3));
}

}  // namespace
}  // namespace shadow
