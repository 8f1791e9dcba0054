// One measured case of shadow-bench: a request variant on one standard scene view.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "oracle/metrics.hpp"
#include "oracle/texel_density.hpp"
#include "wire/types.hpp"

namespace shadow::bench {

struct Case {
  std::string scene, view, variant;
  double wall_median = 0, wall_min = 0, wall_max = 0;  // gRPC round trip, ms
  double engine_median = 0;                            // in-process Engine::render, ms
  double device_ms = 0;                                // sum of the passes' device time
  std::map<std::string, double> passes;                // median device ms per pass
  oracle::VisibilityError error;
  std::vector<oracle::DistanceBand> bands;  // the error by distance from the eye
  oracle::DensityStats density;
  // Shares of the pixels seen on a shadow edge a map can misplace (oracle::boundary_share): in
  // the case's visibility and in the reference's.
  double boundary = 0, reference_boundary = 0;
  // A hard test's error from edge sampling alone (oracle::edge_sampling_estimate, against the
  // same request filtered bilinear 2x2); unset for soft, filtered, AUTO, goal and bias variants.
  std::optional<double> edge_estimate;
  bool soft = false;
  // The light's map as the server reported it (RenderHeader): its case, how many maps it drew
  // (the rendered cube faces, else 1) and their texels in all, map_faces x size^2; for a PSM
  // cube the texel sizes achieved (fractions of the unit cube's edge, else 0).
  std::string light_case;
  uint32_t map_faces = 1;
  uint64_t map_texels = 0;
  double cube_texel_min = 0, cube_texel_max = 0;
  // A quality goal's variant: the goal, and the pick the server reported.
  Quality goal;
  std::optional<QualityPick> quality;
  std::vector<std::string> reused;  // RenderHeader.reused: a goal's steps taken from its probe
};

// The upper median (the middle of an odd count); 0 for none.
double median(std::vector<double> v);

// A case's timed runs, gathered one at a time.
struct TimedRuns {
  std::vector<double> wall;                           // gRPC round trip, ms
  std::map<std::string, std::vector<double>> passes;  // device ms per pass, per run
  void add(double wall_ms, const std::vector<PassTiming>& timings);
  // Sets c's wall_median, wall_min, wall_max, passes (medians) and device_ms (their sum).
  void summarize(Case& c) const;
};

// Fills the case's light_case .. cube_texel_max from the reply's light fit: the maps drawn are
// the rendered cube faces when the fit reports cube faces, else one map; `map_size` is the
// request's edge in texels (each face's for a cube), unless AUTO reports the edge it drew.
void set_map_report(Case& c, const LightFitReport& fit, uint32_t map_size);

}  // namespace shadow::bench
