#include "equal_texels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace shadow::bench {

std::vector<std::string> equal_texel_variants() {
  return {"uniform 2048", "psm 2048", "psm_cube " + std::to_string(kPsmCubeFaceSize),
          "lispsm 2048"};
}

namespace {

// "1/1843 .. 1/1024", or "" when the case drew no PSM cube.
std::string texel_range(const Case& c) {
  if (c.cube_texel_min <= 0 || c.cube_texel_max <= 0) return "";
  char s[64];
  std::snprintf(s, sizeof s, "1/%.0f .. 1/%.0f", 1 / c.cube_texel_min, 1 / c.cube_texel_max);
  return s;
}

double near_rate(const Case& c) {
  return c.bands.empty() ? 0.0 : c.bands.front().error.misclassified_rate();
}
bool has_near(const Case& c) {
  return !c.bands.empty() && c.bands.front().error.both_valid > 0;
}

}  // namespace

void write_equal_texel_section(const std::vector<Case>& cases, std::ostream& md) {
  const std::vector<std::string> variants = equal_texel_variants();
  // The cases come in bench order: by scene and view, then in variant order.
  std::vector<const Case*> rows;
  std::map<std::string, std::map<std::string, const Case*>> by_view;  // view -> variant -> case
  for (const Case& c : cases) {
    if (std::find(variants.begin(), variants.end(), c.variant) == variants.end()) continue;
    rows.push_back(&c);
    by_view[c.scene + "/" + c.view][c.variant] = &c;
  }
  if (rows.empty()) return;
  const std::string near_label =
      rows.front()->bands.empty() ? std::string("none") : rows.front()->bands.front().label();
  md << "\n## Equal texels: uniform, PSM, PSM_CUBE and LiSPSM\n\n"
        "About 4.2 M texels each (uniform, psm and lispsm 2048^2; psm_cube 912^2 per rendered "
        "face). Misclassified = |v - v_ref| > 0.5 against Embree shadow rays; near = the pixels "
        "nearer than the first distance band's edge ("
     << near_label
     << ") to the eye. Summary over the views where all four ran (LiSPSM and PSM_CUBE's single "
        "map need no point light; spot views have no LiSPSM); best = views where the variant "
        "has the lowest rate (ties count for each); the near columns are over the views with "
        "pixels that near.\n\n"
        "| variant | views | mean misclass. | mean near misclass. | best overall | best near |\n"
        "|---|---:|---:|---:|---:|---:|\n";
  char line[768];
  for (const std::string& v : variants) {
    int n = 0, n_near = 0, best_all = 0, best_near = 0;
    double all = 0, near = 0;
    for (const auto& [view, of] : by_view) {
      if (of.size() != variants.size()) continue;
      const Case* c = of.at(v);
      ++n;
      all += c->error.misclassified_rate();
      bool lowest_all = true, lowest_near = true;
      for (const auto& [name, other] : of) {
        lowest_all &= c->error.misclassified_rate() <= other->error.misclassified_rate();
        lowest_near &= near_rate(*c) <= near_rate(*other);
      }
      best_all += lowest_all;
      if (has_near(*c)) ++n_near, near += near_rate(*c), best_near += lowest_near;
    }
    std::snprintf(line, sizeof line, "| %s | %d | %.3f%% | %.3f%% | %d | %d |\n", v.c_str(), n,
                  n ? 100 * all / n : 0.0, n_near ? 100 * near / n_near : 0.0, best_all, best_near);
    md << line;
  }
  md << "\nPer view. Maps = the maps the server drew (the rendered cube faces, else 1), texels = "
        "maps x size^2; a PSM cube that fell back to one map says so in its light case. Cube "
        "texels: the texel sizes the PSM cube achieved, as fractions of the unit cube's edge.\n\n"
        "| scene | view | variant | light case | maps | texels (M) | cube texels | wall ms | "
        "device ms | misclass. | near misclass. |\n"
        "|---|---|---|---|---:|---:|---|---:|---:|---:|---:|\n";
  for (const Case* c : rows) {
    std::snprintf(line, sizeof line,
                  "| %s | %s | %s | %s | %u | %.2f | %s | %.1f | %.1f | %.3f%% | %.3f%% |\n",
                  c->scene.c_str(), c->view.c_str(), c->variant.c_str(), c->light_case.c_str(),
                  c->map_faces, double(c->map_texels) / 1e6, texel_range(*c).c_str(),
                  c->wall_median, c->device_ms, 100 * c->error.misclassified_rate(),
                  100 * near_rate(*c));
    md << line;
  }
}

bool compared_with_auto(const std::string& variant) {
  const std::vector<std::string> fixed = equal_texel_variants();
  return variant == kAutoVariant || std::find(fixed.begin(), fixed.end(), variant) != fixed.end();
}

namespace {

// One view's misclassified rates per compared variant and frame (0: the view's own case).
using FrameRates = std::map<std::string, std::map<int, double>>;

// Over the frames both ran: AUTO's mean, the fixed variant's, and the standard error of the
// mean of their paired difference (0 with one frame).
struct Paired {
  double auto_mean = 0, fixed_mean = 0, se = 0;
  int frames = 0;
};
Paired paired(const std::map<int, double>& a, const std::map<int, double>& f) {
  std::vector<double> d;
  Paired p;
  for (const auto& [frame, rate] : a)
    if (const auto it = f.find(frame); it != f.end()) {
      p.auto_mean += rate, p.fixed_mean += it->second;
      d.push_back(rate - it->second);
    }
  p.frames = int(d.size());
  if (d.empty()) return p;
  p.auto_mean /= p.frames, p.fixed_mean /= p.frames;
  if (d.size() > 1) {
    const double mean = p.auto_mean - p.fixed_mean;
    double ss = 0;
    for (double x : d) ss += (x - mean) * (x - mean);
    p.se = std::sqrt(ss / double(d.size() - 1) / double(d.size()));
  }
  return p;
}

// Device ms of AUTO's trial (LightFitter::try_candidates): its passes under "light_fit.trial.".
double trial_ms(const Case& c) {
  double ms = 0;
  for (const auto& [pass, t] : c.passes)
    if (pass.find("light_fit.trial.") != std::string::npos) ms += t;
  return ms;
}

}  // namespace

void write_auto_section(const std::vector<Case>& cases, const std::vector<FrameError>& frames,
                        std::ostream& md) {
  std::map<std::string, std::vector<const Case*>> of_view;  // view -> fixed variants' cases
  std::map<std::string, FrameRates> rates;                  // view -> variant -> frame -> rate
  std::vector<const Case*> autos;
  for (const Case& c : cases) {
    if (!compared_with_auto(c.variant)) continue;
    rates[c.scene + "/" + c.view][c.variant][0] = c.error.misclassified_rate();
    if (c.variant == kAutoVariant)
      autos.push_back(&c);
    else
      of_view[c.scene + "/" + c.view].push_back(&c);
  }
  for (const FrameError& f : frames)
    rates[f.scene + "/" + f.view][f.variant][f.frame] = f.error.misclassified_rate();
  if (autos.empty()) return;
  md << "\n## TECHNIQUE_AUTO against the best fixed technique at equal texels\n\n"
        "`auto 2048`: the server's pick (its light case gives the pick and the predicted mean "
        "texel footprint in pixels of each candidate, the prediction it decides on) against the "
        "lowest misclassified rate of the equal-texel variants on the same view; gap = AUTO - "
        "best, in percentage points. A rate is deterministic (the same request gives the same "
        "pixels) but hangs on where the shadow edges fall on the texel grid, so every compared "
        "variant also ran on four nudged frames: the light turned "
     << kNudgeDeg << "° each way in azimuth and elevation (a point light moved " << kNudgeM
     << " m along x and z). Frames: AUTO's mean over the view and its nudged frames against the "
        "fixed variant with the lowest mean, and the standard error of the mean of their paired "
        "difference, the noise a gap has to beat. Device ms: AUTO's (of it, its trial of the "
        "candidates at a quarter of their texels) and the best fixed variant's on the view.\n\n"
        "| scene | view | AUTO pick and prediction | AUTO misclass. | best fixed | best "
        "misclass. | gap | frames | AUTO mean | best mean | mean gap +- se | AUTO near | best "
        "near | AUTO device ms (trial) | best device ms |\n"
        "|---|---|---|---:|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|\n";
  char line[1280];
  int views = 0, met = 0, framed = 0, mean_met = 0, within_noise = 0;
  double gap_sum = 0;
  std::vector<double> cost_ratios, trial_shares;  // AUTO over the best's device ms; trial/AUTO
  for (const Case* a : autos) {
    const std::string key = a->scene + "/" + a->view;
    const auto it = of_view.find(key);
    if (it == of_view.end()) continue;
    const Case* best = it->second.front();
    const Case* best_near = best;
    for (const Case* c : it->second) {
      if (c->error.misclassified_rate() < best->error.misclassified_rate()) best = c;
      if (near_rate(*c) < near_rate(*best_near)) best_near = c;
    }
    const double gap = 100 * (a->error.misclassified_rate() - best->error.misclassified_rate());
    ++views, met += gap <= 0.0;
    // The fixed variant with the lowest mean over the frames AUTO ran on.
    const FrameRates& view_rates = rates[key];
    const std::map<int, double>& auto_rates = view_rates.at(kAutoVariant);
    std::string best_mean_variant;
    Paired p;
    for (const Case* c : it->second) {
      const Paired q = paired(auto_rates, view_rates.at(c->variant));
      if (best_mean_variant.empty() || q.fixed_mean < p.fixed_mean)
        p = q, best_mean_variant = c->variant;
    }
    const double mean_gap = 100 * (p.auto_mean - p.fixed_mean), se = 100 * p.se;
    if (p.frames > 1) {
      ++framed, gap_sum += mean_gap;
      mean_met += mean_gap <= 0.0;
      within_noise += mean_gap <= se;
    }
    std::snprintf(line, sizeof line,
                  "| %s | %s | %s | %.3f%% | %s | %.3f%% | %+.3f | %d | %.3f%% | %.3f%% (%s) | "
                  "%+.3f +- %.3f | %.3f%% | %.3f%% (%s) | %.1f (%.1f) | %.1f |\n",
                  a->scene.c_str(), a->view.c_str(), a->light_case.c_str(),
                  100 * a->error.misclassified_rate(), best->variant.c_str(),
                  100 * best->error.misclassified_rate(), gap, p.frames, 100 * p.auto_mean,
                  100 * p.fixed_mean, best_mean_variant.c_str(), mean_gap, se, 100 * near_rate(*a),
                  100 * near_rate(*best_near), best_near->variant.c_str(), a->device_ms,
                  trial_ms(*a), best->device_ms);
    md << line;
    if (best->device_ms > 0 && a->device_ms > 0) {
      cost_ratios.push_back(a->device_ms / best->device_ms);
      trial_shares.push_back(trial_ms(*a) / a->device_ms);
    }
  }
  md << "\nOn the views themselves, AUTO as good as the best fixed technique (gap <= 0) on " << met
     << " of " << views << " views.";
  if (framed) {
    std::snprintf(line, sizeof line,
                  " Over their frames, AUTO's mean as good as the best fixed mean on %d of %d "
                  "views, worse by no more than the standard error on %d; mean gap %+.3f "
                  "points.",
                  mean_met, framed, within_noise, gap_sum / framed);
    md << line;
  }
  if (!cost_ratios.empty()) {
    std::snprintf(line, sizeof line,
                  " AUTO's device time, median over the views: %.2fx the best fixed variant's "
                  "(range %.2f-%.2fx); its trial %.0f%% of it.",
                  median(cost_ratios), *std::min_element(cost_ratios.begin(), cost_ratios.end()),
                  *std::max_element(cost_ratios.begin(), cost_ratios.end()),
                  100 * median(trial_shares));
    md << line;
  }
  md << '\n';
}

}  // namespace shadow::bench
