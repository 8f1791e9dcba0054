#include "engine/choose/calibration.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "engine/plan/light_request.hpp"
#include "engine/plan/technique.hpp"
#include "engine/plan/validate.hpp"

namespace shadow {

extern const char* const kBuiltInCalibration;  // generated from data/calibration.csv

namespace {

constexpr std::string_view kHeader =
    "technique,footprint_px_max,misclassified_per_boundary_pixel,pixels";
// Tables written before the probe counted per pixel: their rates mean something else.
constexpr std::string_view kPerPixelHeader = "technique,footprint_px_max,misclassified_rate,pixels";
constexpr std::string_view kErrorHeader = "error_margin,value,views";
constexpr std::string_view kTimeHeader = "device_time,value,measured_on";
constexpr std::string_view kMarginRow = "margin_p90.";     // + a technique label [+ "." size]
constexpr std::string_view kMedianRow = "margin_median.";  // + a technique label + "." size
constexpr Technique kCalibrated[] = {Technique::kUniform, Technique::kLispsm, Technique::kPsm,
                                     Technique::kPsmCube, Technique::kCube};

// A whole field as a double, or NaN.
double number(std::string_view s) {
  if (s == "inf") return INFINITY;
  std::string text(s);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() ? v : NAN;
}

// The calibrated technique a label names, or null.
const Technique* calibrated(std::string_view label) {
  const Technique* t = std::find_if(std::begin(kCalibrated), std::end(kCalibrated),
                                    [&](Technique c) { return label == technique_label(c); });
  return t == std::end(kCalibrated) ? nullptr : t;
}

// A whole field as a count: a whole number >= 0, or NaN.
double count(std::string_view s) {
  const double v = number(s);
  return v >= 0 && v < 1e18 && v == std::floor(v) ? v : NAN;
}

// A map size field: a whole number in [1, kMaxMapSize], or NaN.
double map_size(std::string_view s) {
  const double v = count(s);
  return v >= 1 && v <= kMaxMapSize ? v : NAN;
}

}  // namespace

Calibration Calibration::parse(std::string_view text, const std::string& source) {
  Table table;
  DeviceTimes times;
  ErrorMargins errors;
  std::array<bool, kCostRates> rate_seen{};
  // The sized margins and which of their rows came (1: median, 2: p90).
  std::map<std::pair<Technique, uint32_t>, std::pair<DeviceTimes::SizedMargin, int>> sized_seen;
  enum { kNone, kBins, kErrors, kTimes } section = kNone;
  size_t line_no = 0;
  const auto fail = [&](const std::string& why) {
    throw std::invalid_argument(source + ":" + std::to_string(line_no) + ": " + why);
  };
  const std::vector<CalibrationBin>* open = nullptr;  // the technique whose rows come now
  const auto close = [&] {
    if (open && !std::isinf(open->back().footprint_max))
      fail("the bins before this line do not end with footprint_px_max inf");
    open = nullptr;
  };
  while (!text.empty()) {
    ++line_no;
    const size_t eol = text.find('\n');
    std::string_view line = text.substr(0, eol);
    text = eol == std::string_view::npos ? std::string_view{} : text.substr(eol + 1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty() || line.front() == '#') continue;
    if (section == kNone) {
      if (line == kPerPixelHeader)
        fail(
            "a table per pixel, from before the boundary probe: write a new one with "
            "shadow-bench --calibration");
      if (line != kHeader) fail("expected the header \"" + std::string(kHeader) + "\"");
      section = kBins;
      continue;
    }
    if (section == kBins && line == kErrorHeader) {
      close();
      section = kErrors;
      continue;
    }
    if (line == kTimeHeader) {
      if (section != kErrors)
        fail("no \"" + std::string(kErrorHeader) +
             "\" section before the device times (a table from before the error margins): "
             "write a new one with shadow-bench --calibration");
      section = kTimes;
      continue;
    }
    const size_t fields = section == kBins ? 4 : 3;
    std::string_view f[4];
    for (size_t i = 0; i < fields; ++i) {
      const size_t comma = line.find(',');
      if ((comma == std::string_view::npos) != (i == fields - 1))
        fail("expected " + std::to_string(fields) + " comma-separated fields");
      f[i] = line.substr(0, comma);
      line = comma == std::string_view::npos ? std::string_view{} : line.substr(comma + 1);
    }
    if (section == kErrors) {
      const size_t dot = f[0].find('.');
      const Technique* t = calibrated(f[0].substr(0, dot));
      if (!t || dot == std::string_view::npos)
        fail("expected <technique>.<size> (uniform, lispsm, psm, psm_cube or cube), got \"" +
             std::string(f[0]) + "\"");
      const double size = map_size(f[0].substr(dot + 1));
      if (std::isnan(size))
        fail("bad map size in \"" + std::string(f[0]) + "\" (a whole number in [1, 8192])");
      const double value = number(f[1]), views = count(f[2]);
      if (!(value >= 0 && std::isfinite(value)))
        fail("the error margin of " + std::string(f[0]) + " must be a number >= 0");
      if (std::isnan(views)) fail("views must be a whole number >= 0");
      if (!errors.emplace(std::pair{*t, uint32_t(size)}, ErrorMargin{value, uint64_t(views)})
               .second)
        fail("error margin " + std::string(f[0]) + " twice");
      continue;
    }
    if (section == kTimes) {
      const double value = number(f[1]), on = count(f[2]);
      if (std::isnan(on)) fail("measured_on must be a whole number >= 0");
      const bool p90 = f[0].starts_with(kMarginRow), median = f[0].starts_with(kMedianRow);
      if (p90 || median) {
        const std::string_view what = f[0].substr((p90 ? kMarginRow : kMedianRow).size());
        const size_t dot = what.find('.');
        const Technique* t = calibrated(what.substr(0, dot));
        if (!t)
          fail("unknown technique in \"" + std::string(f[0]) +
               "\" (expected uniform, lispsm, psm, psm_cube or cube)");
        if (!(value > 0 && std::isfinite(value))) fail(std::string(f[0]) + " must be a number > 0");
        if (dot == std::string_view::npos) {
          if (median)
            fail(std::string(f[0]) + " needs a map size (margin_median.<technique>.<size>)");
          if (times.margins.count(*t)) fail(std::string(f[0]) + " twice");
          times.margins[*t] = {value, uint64_t(on)};
          continue;
        }
        const double size = map_size(what.substr(dot + 1));
        if (std::isnan(size))
          fail("bad map size in \"" + std::string(f[0]) + "\" (a whole number in [1, 8192])");
        auto& [sized, seen] = sized_seen[{*t, uint32_t(size)}];
        if (seen & (p90 ? 2 : 1)) fail(std::string(f[0]) + " twice");
        seen |= p90 ? 2 : 1;
        (p90 ? sized.p90 : sized.median) = value;
        if (seen == 3 && sized.cases != uint64_t(on))
          fail(std::string(f[0]) + ": its median and 90th percentile count different cases");
        sized.cases = uint64_t(on);
        continue;
      }
      size_t r = 0;
      while (r < kCostRates && f[0] != cost_rate_label(CostRate(r))) ++r;
      if (r == kCostRates) fail("unknown device_time \"" + std::string(f[0]) + "\"");
      if (rate_seen[r]) fail(std::string(f[0]) + " twice");
      if (!(value >= 0 && std::isfinite(value))) fail(std::string(f[0]) + " must be a number >= 0");
      rate_seen[r] = true;
      times.rates.ns[r] = value, times.measured_on[r] = uint64_t(on);
      continue;
    }
    const Technique* t = calibrated(f[0]);
    if (!t)
      fail("unknown technique \"" + std::string(f[0]) +
           "\" (expected uniform, lispsm, psm, psm_cube or cube)");
    std::vector<CalibrationBin>& bins = table[*t];
    if (&bins != open) {
      if (!bins.empty()) fail("technique " + std::string(f[0]) + "'s rows are not together");
      close();
      open = &bins;
    }
    const double max = number(f[1]), rate = number(f[2]), pixels = count(f[3]);
    if (!(max > 0)) fail("footprint_px_max must be a number > 0 or inf");
    if (!bins.empty() && !(max > bins.back().footprint_max))
      fail("footprint_px_max must increase from row to row");
    if (!(rate >= 0 && std::isfinite(rate)))
      fail("misclassified_per_boundary_pixel must be a number >= 0");
    if (std::isnan(pixels)) fail("pixels must be a whole number >= 0");
    bins.push_back({max, rate, uint64_t(pixels)});
  }
  if (section == kNone) throw std::invalid_argument(source + ": no header (an empty file?)");
  ++line_no;
  close();
  for (Technique t : {Technique::kUniform, Technique::kLispsm, Technique::kPsm})
    if (!table.count(t))
      throw std::invalid_argument(source + ": no bins for " + technique_label(t) +
                                  " (the quality goals' candidates need uniform, lispsm and psm)");
  if (section != kTimes)
    throw std::invalid_argument(source + ": no \"" + std::string(kTimeHeader) +
                                "\" rows (a table from before the time side): write a new one "
                                "with shadow-bench --calibration");
  for (size_t r = 0; r < kCostRates; ++r)
    if (!rate_seen[r])
      throw std::invalid_argument(source + ": no device_time row for " +
                                  cost_rate_label(CostRate(r)) +
                                  " (a table from before that rate: write a new one with "
                                  "shadow-bench --calibration)");
  for (Technique t : {Technique::kUniform, Technique::kLispsm, Technique::kPsm})
    if (!times.margins.count(t))
      throw std::invalid_argument(source + ": no device_time row for margin_p90." +
                                  technique_label(t));
  for (const auto& [key, entry] : sized_seen) {
    if (entry.second != 3)
      throw std::invalid_argument(source + ": margin_" + (entry.second == 1 ? "median" : "p90") +
                                  "." + technique_label(key.first) + "." +
                                  std::to_string(key.second) + " without its margin_" +
                                  (entry.second == 1 ? "p90" : "median") + " row");
    times.sized[key] = entry.first;
  }
  return Calibration(std::move(table), times, std::move(errors));
}

Calibration Calibration::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot be read: " + std::strerror(errno));
  constexpr size_t kMaxBytes = size_t{1} << 20;
  std::string text(kMaxBytes + 1, '\0');
  in.read(text.data(), std::streamsize(text.size()));
  text.resize(size_t(in.gcount()));
  if (text.size() > kMaxBytes) throw std::invalid_argument(path + ": larger than 1 MiB");
  return parse(text, path);
}

const Calibration& Calibration::built_in() {
  static const Calibration table = parse(kBuiltInCalibration, "data/calibration.csv (built in)");
  return table;
}

Calibration::Calibration(Table table, DeviceTimes times, ErrorMargins errors)
    : table_(std::move(table)), errors_(std::move(errors)), times_(times) {
  for (const auto& [technique, measured] : table_) {
    // A sparse bin takes the rate of the next coarser bin with enough pixels, so its few pixels
    // neither promise a perfect map nor spoil one. Where there is none: for PSM_CUBE, PSM's
    // prediction at that footprint (its faces are PSM maps; the standard views give the cube few
    // large footprints, and its last dense rate would promise them the error of 8 px); else the
    // nearest finer dense bin's.
    const auto dense = [&](size_t j) { return measured[j].pixels >= kMinBinPixels; };
    const auto kin = monotone_.find(Technique::kPsm);  // done: the table is in enum order
    const auto kin_rate = [&](double footprint_max) -> std::optional<double> {
      if (technique != Technique::kPsmCube || kin == monotone_.end()) return std::nullopt;
      for (const CalibrationBin& b : kin->second)
        if (b.footprint_max >= footprint_max) return b.per_boundary;
      return std::nullopt;
    };
    std::vector<CalibrationBin> bins = measured;
    for (size_t i = 0; i < bins.size(); ++i) {
      size_t from = i;
      while (from < bins.size() && !dense(from)) ++from;
      if (from == bins.size()) {
        if (const std::optional<double> r = kin_rate(bins[i].footprint_max)) {
          bins[i].per_boundary = *r;
          continue;
        }
        for (from = i; from > 0 && !dense(from);) --from;
      }
      if (dense(from)) bins[i].per_boundary = measured[from].per_boundary;
    }
    // Pool adjacent violators: merge a bin into the block before it while its rate is lower,
    // the block's rate the pixel-weighted mean, then give every bin its block's rate.
    struct Block {
      double rate, weight;
      size_t bins;
    };
    std::vector<Block> blocks;
    for (const CalibrationBin& b : bins) {
      blocks.push_back({b.per_boundary, std::max(double(b.pixels), 1.0), 1});
      while (blocks.size() > 1 && blocks.back().rate < blocks[blocks.size() - 2].rate) {
        const Block top = blocks.back();
        blocks.pop_back();
        Block& below = blocks.back();
        below.rate =
            (below.rate * below.weight + top.rate * top.weight) / (below.weight + top.weight);
        below.weight += top.weight, below.bins += top.bins;
      }
    }
    std::vector<CalibrationBin>& out = monotone_[technique] = bins;
    size_t i = 0;
    for (const Block& b : blocks)
      for (size_t k = 0; k < b.bins; ++k) out[i++].per_boundary = b.rate;
  }
}

double Calibration::per_boundary_at(Technique technique, double footprint_px) const {
  if (std::isnan(footprint_px)) return 0.0;
  const std::vector<CalibrationBin>& bins = monotone_.at(technique);
  for (const CalibrationBin& b : bins)
    if (footprint_px <= b.footprint_max) return b.per_boundary;
  return bins.back().per_boundary;
}

double Calibration::error_margin(Technique technique, uint32_t map_size) const {
  const auto it = errors_.find({technique, map_size});
  return it != errors_.end() && it->second.views >= kMinMarginViews ? it->second.value : 1.0;
}

double DeviceTimes::margin(Technique technique) const {
  const auto it = margins.find(technique);
  if (it != margins.end()) return it->second.p90;
  double largest = 1;
  for (const auto& [t, m] : margins) largest = std::max(largest, m.p90);
  return largest;
}

std::pair<double, double> DeviceTimes::factors(Technique technique, uint32_t map_size) const {
  const auto it = sized.find({technique, map_size});
  if (it != sized.end() && it->second.cases >= kMinSizedCases)
    return {it->second.median, it->second.p90};
  return {1.0, margin(technique)};
}

PredictedTime Calibration::predict_time(const RenderRequest& request, const Plan& plan,
                                        const MapLoads& loads) const {
  const Technique t = request.lights.empty() ? Technique::kUniform
                                             : resolved_technique(request.shadow_map.technique,
                                                                  request.lights[0].type);
  const double at_rates = estimate_cost(request, plan, times_.rates, loads).ms;
  const auto [typical, p90] = times_.factors(t, request.shadow_map.size);
  return {at_rates * typical, at_rates * p90};
}

std::string Calibration::to_csv(const std::string& comment) const {
  std::ostringstream out;
  std::istringstream lines(comment);
  for (std::string l; std::getline(lines, l);) out << "# " << l << '\n';
  out << kHeader << '\n';
  char row[128];
  for (const auto& [technique, bins] : table_)
    for (const CalibrationBin& b : bins) {
      char max[32];
      if (std::isinf(b.footprint_max))
        std::snprintf(max, sizeof max, "inf");
      else
        std::snprintf(max, sizeof max, "%.9g", b.footprint_max);
      std::snprintf(row, sizeof row, "%s,%s,%.9g,%llu\n", technique_label(technique), max,
                    b.per_boundary, static_cast<unsigned long long>(b.pixels));
      out << row;
    }
  out << kErrorHeader << '\n';
  for (const auto& [key, m] : errors_) {
    std::snprintf(row, sizeof row, "%s.%u,%.6g,%llu\n", technique_label(key.first), key.second,
                  m.value, static_cast<unsigned long long>(m.views));
    out << row;
  }
  out << kTimeHeader << '\n';
  for (size_t r = 0; r < kCostRates; ++r) {
    std::snprintf(row, sizeof row, "%s,%.6g,%llu\n", cost_rate_label(CostRate(r)),
                  times_.rates.ns[r], static_cast<unsigned long long>(times_.measured_on[r]));
    out << row;
  }
  for (const auto& [technique, m] : times_.margins) {
    std::snprintf(row, sizeof row, "%s%s,%.6g,%llu\n", std::string(kMarginRow).c_str(),
                  technique_label(technique), m.p90, static_cast<unsigned long long>(m.cases));
    out << row;
  }
  for (const auto& [key, m] : times_.sized)
    for (const auto& [prefix, value] : {std::pair{kMedianRow, m.median}, {kMarginRow, m.p90}}) {
      std::snprintf(row, sizeof row, "%s%s.%u,%.6g,%llu\n", std::string(prefix).c_str(),
                    technique_label(key.first), key.second, value,
                    static_cast<unsigned long long>(m.cases));
      out << row;
    }
  return out.str();
}

}  // namespace shadow
