#include "goal_ceiling.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "engine/choose/calibration.hpp"
#include "engine/plan/cost_fit.hpp"
#include "quality_section.hpp"

namespace shadow::bench {
namespace {

using Configuration = std::pair<Technique, uint32_t>;

struct Candidate {
  Configuration configuration;
  double rate = 0;          // its fixed run's misclassified rate
  double cost[2] = {0, 0};  // the goal's cost had it picked this: [0] with the measures
};

struct Goal {
  std::string variant;
  std::string view;  // "scene/view"
  double bound = 0;
  const Case* cheapest = nullptr;  // the cheapest fixed run that met the bound
  std::vector<Candidate> candidates;
};

std::string view_of(const Case& c) {
  return c.scene + "/" + c.view;
}

bool is_error_goal(const Case& c) {
  return c.goal.goal == Quality::Goal::kMaxError && c.quality && !c.quality->candidates.empty();
}

// The max_error goals that some fixed run met, with their candidates' rates and costs.
std::vector<Goal> replayable_goals(const std::vector<Case>& cases) {
  const auto fixed = fixed_by_view(cases);
  std::vector<Goal> goals;
  for (const Case& g : cases) {
    if (!is_error_goal(g)) continue;
    const auto it = fixed.find(view_of(g));
    if (it == fixed.end()) continue;
    const Case* best = cheapest_meeting(g.goal.value, it->second);
    if (!best) continue;
    Goal goal{g.variant, view_of(g), g.goal.value, best, {}};
    for (const QualityCandidate& c : g.quality->candidates) {
      const Case* run = fixed_run(it->second, c.technique, c.size);
      if (!run) continue;
      const Case picked = as_picked(g, c.technique, c.size);
      goal.candidates.push_back(
          {{c.technique, c.size},
           own_rate(*run),
           {goal_cost_ms(picked, it->second, true), goal_cost_ms(picked, it->second, false)}});
    }
    if (!goal.candidates.empty()) goals.push_back(std::move(goal));
  }
  return goals;
}

// Sample standard deviation; 0 for fewer than two values.
double spread(const std::vector<double>& x) {
  if (x.size() < 2) return 0;
  double mean = 0, sum = 0;
  for (double v : x) mean += v / double(x.size());
  for (double v : x) sum += (v - mean) * (v - mean);
  return std::sqrt(sum / double(x.size() - 1));
}

}  // namespace

std::vector<CeilingPoint> goal_ceiling(const std::vector<Case>& cases,
                                       const std::vector<double>& sigmas, int draws,
                                       uint64_t seed) {
  const std::vector<Goal> goals = replayable_goals(cases);
  std::vector<CeilingPoint> points;
  if (goals.empty()) return points;
  // Each view's configurations once, in a fixed order: one draw of z each.
  std::map<std::pair<std::string, Configuration>, double> rate_of;
  for (const Goal& g : goals)
    for (const Candidate& c : g.candidates) rate_of[{g.view, c.configuration}] = c.rate;
  std::map<std::string, int> views_of;  // comparable views per goal variant
  for (const Goal& g : goals) ++views_of[g.variant];
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  for (double sigma : sigmas) {
    std::map<std::string, double> within[2];  // by goal variant: [0] with the measures
    for (int d = 0; d < draws; ++d) {
      std::map<std::pair<std::string, Configuration>, double> predicted;
      std::map<Configuration, std::pair<std::vector<double>, std::vector<double>>> pairs;
      for (const auto& [key, rate] : rate_of) {
        const double p = rate * std::exp(sigma * normal(rng));
        predicted[key] = p;
        pairs[key.second].first.push_back(p);
        pairs[key.second].second.push_back(rate);
      }
      std::map<Configuration, double> margin;  // as the calibration counts it
      for (const auto& [configuration, pm] : pairs)
        margin[configuration] = pm.first.size() >= Calibration::kMinMarginViews
                                    ? margin_quantile(pm.first, pm.second, kErrorQuantile)
                                    : 1.0;
      for (const Goal& g : goals)
        for (int m = 0; m < 2; ++m) {
          const Candidate* pick = nullptr;
          double pick_error = INFINITY;
          for (const Candidate& c : g.candidates) {
            const double e = predicted[{g.view, c.configuration}] * margin[c.configuration];
            const bool meets = e <= g.bound, picked_meets = pick_error <= g.bound;
            if (!pick || (meets && (!picked_meets || c.cost[m] < pick->cost[m])) ||
                (!meets && !picked_meets && e < pick_error))
              pick = &c, pick_error = e;
          }
          within[m][g.variant] += pick->rate <= g.bound && within_cost(pick->cost[m], *g.cheapest);
        }
    }
    for (int m = 0; m < 2; ++m)
      for (const auto& [variant, views] : views_of)
        points.push_back({variant, sigma, m == 0, within[m][variant] / draws, views});
  }
  return points;
}

Spreads prediction_spreads(const std::vector<Case>& cases, const std::vector<FrameError>& frames) {
  Spreads s;
  const auto fixed = fixed_by_view(cases);
  std::vector<double> logs;
  std::set<std::tuple<std::string, Technique, uint32_t>> seen;  // a view's candidate once
  for (const Case& g : cases) {
    if (!is_error_goal(g)) continue;
    const auto it = fixed.find(view_of(g));
    if (it == fixed.end()) continue;
    for (const QualityCandidate& c : g.quality->candidates) {
      const Case* run = fixed_run(it->second, c.technique, c.size);
      if (!run || !seen.insert({view_of(g), c.technique, c.size}).second) continue;
      if (c.predicted_error > 0 && own_rate(*run) > 0)
        logs.push_back(std::log(c.predicted_error / own_rate(*run)));
    }
  }
  s.prediction = spread(logs), s.predictions = logs.size();
  logs.clear();
  std::map<std::tuple<std::string, std::string, std::string>, std::vector<double>> over_frames;
  for (const Case& c : cases) {
    if (!is_fixed_configuration(c.variant) || own_rate(c) <= 0) continue;
    if (c.edge_estimate && *c.edge_estimate > 0)
      logs.push_back(std::log(*c.edge_estimate / own_rate(c)));
    over_frames[{c.scene, c.view, c.variant}].push_back(std::log(own_rate(c)));
  }
  s.edge_estimate = spread(logs), s.estimates = logs.size();
  for (const FrameError& f : frames) {
    const auto it = over_frames.find({f.scene, f.view, f.variant});
    if (it != over_frames.end() && f.error.misclassified_rate() > 0)
      it->second.push_back(std::log(f.error.misclassified_rate()));
  }
  std::vector<double> per_run;
  for (const auto& [run, x] : over_frames)
    if (x.size() >= 2) per_run.push_back(spread(x));
  s.frame_runs = per_run.size();
  if (!per_run.empty()) {
    std::sort(per_run.begin(), per_run.end());
    const size_t n = per_run.size();
    s.frames_median = n % 2 ? per_run[n / 2] : 0.5 * (per_run[n / 2 - 1] + per_run[n / 2]);
    for (double x : per_run) s.frames_mean += x / double(n);
  }
  return s;
}

void write_goal_ceiling(const std::vector<Case>& cases, const std::vector<FrameError>& frames,
                        std::ostream& md, std::ostream& csv) {
  const std::vector<double> sigmas = {0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7};
  constexpr int kDraws = 200;
  const std::vector<CeilingPoint> points = goal_ceiling(cases, sigmas, kDraws, 17);
  if (points.empty()) return;
  const Spreads s = prediction_spreads(cases, frames);
  // Each goal as it ran: views met within 1.5x (the quality section's judgement).
  const auto fixed = fixed_by_view(cases);
  std::map<std::string, int> actual;
  for (const Case& g : cases) {
    if (!is_error_goal(g)) continue;
    const auto it = fixed.find(view_of(g));
    const Case* best = it == fixed.end() ? nullptr : cheapest_meeting(g.goal.value, it->second);
    if (best)
      actual[g.variant] +=
          own_rate(g) <= g.goal.value && within_cost(goal_cost_ms(g, it->second), *best);
  }
  csv << "kind,name,sigma,measures,within,views\n";
  for (const CeilingPoint& p : points)
    csv << "curve," << p.goal << ',' << p.sigma << ',' << int(p.measures) << ',' << p.within << ','
        << p.views << '\n';
  for (const auto& [name, value] : {std::pair<const char*, double>{"prediction", s.prediction},
                                    {"edge_estimate", s.edge_estimate},
                                    {"frames_median", s.frames_median},
                                    {"frames_mean", s.frames_mean}})
    csv << "spread," << name << ',' << value << ",,,\n";
  std::map<std::string, int> views;
  for (const CeilingPoint& p : points) views[p.goal] = p.views;
  for (const auto& [goal, n] : actual)
    csv << "actual," << goal << ',' << s.prediction << ",1," << n << ',' << views[goal] << '\n';

  char line[512];
  md << "\n## Error goals: the prediction they need (goal_ceiling.png)\n\n"
        "Each max_error goal replayed "
     << kDraws
     << " times per spread: every candidate's error predicted as its fixed run's measured rate "
        "times exp(sigma z), z standard normal per view and configuration, times the margin "
        "the calibration would set on such predictions; the pick the candidate predicted to "
        "meet the bound at the least cost the goal would have had (times known, so that only "
        "the error prediction varies). Views met within 1.5x of the cheapest fixed "
        "configuration that met the bound, mean over the draws, with the probe's measures "
        "(boundary count, depth range, samples, raster loads) at their measured cost and at "
        "none. The goal is 90% of the views.\n\n"
        "| sigma |";
  std::vector<std::string> goal_names;
  for (const auto& [goal, n] : views) goal_names.push_back(goal);
  for (const std::string& g : goal_names) md << " " << g << " |";
  for (const std::string& g : goal_names) md << " " << g << ", no measures |";
  md << "\n|---:|";
  for (size_t i = 0; i < 2 * goal_names.size(); ++i) md << "---:|";
  md << '\n';
  for (double sigma : sigmas) {
    std::snprintf(line, sizeof line, "| %.2f |", sigma);
    md << line;
    for (bool measures : {true, false})
      for (const std::string& g : goal_names)
        for (const CeilingPoint& p : points)
          if (p.sigma == sigma && p.measures == measures && p.goal == g) {
            std::snprintf(line, sizeof line, " %.1f of %d |", p.within, p.views);
            md << line;
          }
    md << '\n';
  }
  std::snprintf(line, sizeof line,
                "\nSpreads, sd of log(estimate / measured): the server's predictions of the "
                "goals' candidates %.2f (%zu); the edge-sampling estimate of the fixed runs "
                "%.2f (%zu), which needs each map drawn; the measured rate itself over a view "
                "and its nudged frames, median %.2f and mean %.2f over %zu fixed runs",
                s.prediction, s.predictions, s.edge_estimate, s.estimates, s.frames_median,
                s.frames_mean, s.frame_runs);
  md << line << ", which no prediction that does not draw the frame gets below. As the goals ran:";
  for (const std::string& g : goal_names) {
    std::snprintf(line, sizeof line, " %s %d of %d;", g.c_str(), actual[g], views[g]);
    md << line;
  }
  md << " (the quality section's judgement).\n";
}

}  // namespace shadow::bench
