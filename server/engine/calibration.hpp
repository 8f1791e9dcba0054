// The accuracy side of a quality goal (RenderRequest::quality): how often a camera pixel's hard
// shadow test is wrong, per technique, as a function of the texel footprint there (the size in
// pixels of one map texel on the surface, as PRODUCT_TEXEL_DENSITY measures it).
// shadow-bench --calibration measures it against the Embree oracle over the standard views and
// writes it as CSV; the server embeds data/calibration.csv and may load another with
// --calibration at start-up.
//
// Format: '#' comment lines, the header "technique,footprint_px_max,misclassified_rate,pixels",
// then per technique (technique_label: uniform, lispsm, psm, psm_cube, cube; each at most once,
// its rows together) one row per bin in increasing footprint_px_max, its last "inf": the share
// of the bin's pixels misclassified, and how many pixels it was measured on. A footprint falls
// in the first bin whose footprint_px_max holds it.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "wire/types.hpp"

namespace shadow {

struct CalibrationBin {
  double footprint_max = 0;  // px; +inf for the last
  double misclassified = 0;  // share, [0, 1]
  uint64_t pixels = 0;
};

class Calibration {
 public:
  using Table = std::map<Technique, std::vector<CalibrationBin>>;

  // Throws std::invalid_argument naming `source`, the line and what is wrong.
  static Calibration parse(std::string_view text, const std::string& source);
  // The file at `path` (at most 1 MiB), parsed; throws std::invalid_argument naming it.
  static Calibration load(const std::string& path);
  // The table built into the server (data/calibration.csv at build time).
  static const Calibration& built_in();

  // The predicted misclassified share of `technique` at a footprint: NaN (a ray off every map)
  // is 0, nothing there can be shadowed; a technique without bins throws std::out_of_range.
  // Predictions never fall as the footprint grows (a finer map is never predicted worse): the
  // measured rates are pooled where they do, adjacent bins averaged by their pixels.
  double error_at(Technique technique, double footprint_px) const;
  bool has(Technique technique) const { return table_.count(technique) != 0; }
  std::string to_csv(const std::string& comment) const;
  const Table& table() const { return table_; }

  explicit Calibration(Table table);

 private:
  Table table_;     // as measured
  Table monotone_;  // what error_at reads
};

}  // namespace shadow
