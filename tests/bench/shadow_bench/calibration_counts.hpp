// shadow-bench --calibration: what a quality goal's calibration table
// (engine/choose/calibration.hpp) is made of, counted over the hard-test cases of the standard
// views.
//
// The error side: per technique and texel-footprint bin, the pixels, how many of them are
// misclassified against shadow rays, and the boundary pixels they stand for: each pixel counts
// the probe's boundary share in its cell of the goals' sample grid (the "uniform 512" case, the
// probe's map; oracle::local_boundary_share), as a goal weighs a sample by its cell's edges.
// Bins double from 1/16 px. Only pixels whose seen side faces the light count: the others are
// attached shadows, which no map misclassifies (engine/choose/auto_pick.hpp, faces_light), and the
// goal predicts them so.
// The error margins: each fixed configuration's measured misclassified share per view, and what
// a goal predicted for it there from the counted bins (goal_predictions.hpp, a second pass).
// The time side: each case's steps as estimate_cost prices them (with the raster loads its maps
// reported) beside their measured passes, for fit_rates (engine/plan/cost_fit.hpp), and each case's
// device time, for the margins (per technique, and per technique and map size).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "engine/choose/calibration.hpp"
#include "engine/plan/cost_fit.hpp"
#include "wire/types.hpp"

namespace shadow::bench {

class CalibrationCounts {
 public:
  static constexpr double kEdges[] = {0.0625, 0.125, 0.25, 0.5, 1,   2,   4,
                                      8,      16,    32,   64,  128, 256, INFINITY};
  // The predicted device time covers this share of each technique's cases (DeviceTimes).
  static constexpr double kMarginQuantile = 0.9;

  // One case of technique `t` that ran: its texel footprints, visibility, the reference, which
  // pixels' seen side faces the light (1) and the probe's boundary share around each pixel.
  void add_error(Technique t, const std::vector<float>& footprint, const std::vector<float>& vis,
                 const std::vector<float>& ref, const std::vector<uint8_t>& faces_light,
                 const std::vector<float>& boundary_share);
  // One case's request (its technique and map size those that ran), its maps' raster loads as
  // its reply reported them, the median device ms of each of its passes and their sum.
  void add_time(const RenderRequest& request, const MapLoads& loads,
                const std::map<std::string, double>& passes, double device_ms);

  // A fixed technique's case: its measured misclassified share on the view ("scene/view").
  void add_measured(const std::string& view, Technique t, uint32_t map_size, double misclassified);
  // A goal's candidates on the view, predicted from table()'s bins without error margins.
  void add_predicted(const std::string& view, const std::vector<QualityCandidate>& candidates);

  // The bins and times; the error margins of the configurations both measured and predicted
  // (none before add_predicted).
  Calibration table() const;

 private:
  struct Counts {
    uint64_t pixels[std::size(kEdges)] = {}, wrong[std::size(kEdges)] = {};
    double boundary[std::size(kEdges)] = {};
  };
  struct TimedCase {
    std::vector<StepCost> steps;
    double device_ms;
    Technique technique;  // that ran
    uint32_t map_size;    // drawn
  };
  using Configuration = std::pair<Technique, uint32_t>;
  std::map<std::pair<std::string, Configuration>, double> measured_, predicted_;
  std::map<Technique, Counts> of_;
  std::vector<StepTime> steps_;
  std::vector<TimedCase> cases_;
};

}  // namespace shadow::bench
