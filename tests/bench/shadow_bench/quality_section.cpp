#include "quality_section.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>

#include "engine/choose/quality_pick.hpp"
#include "wire/names.hpp"

namespace shadow::bench {

bool is_fixed_configuration(const std::string& variant) {
  for (const char* t : {"uniform ", "psm ", "lispsm ", "auto "}) {
    const std::string prefix = t;
    if (variant.rfind(prefix, 0) != 0 || variant.size() == prefix.size()) continue;
    bool digits = true;
    for (size_t i = prefix.size(); i < variant.size(); ++i)
      digits &= std::isdigit(static_cast<unsigned char>(variant[i])) != 0;
    if (digits) return true;
  }
  return false;
}

namespace {

// A pass of the bench's own texel-density product.
bool density_pass(const std::string& pass) {
  return pass.find("texel_density") != std::string::npos;
}

// The run among `fixed` named `variant`, if the sweep has one.
const Case* find_variant(const std::vector<const Case*>& fixed, const std::string& variant) {
  for (const Case* f : fixed)
    if (f->variant == variant) return f;
  return nullptr;
}

}  // namespace

const Case* fixed_run(const std::vector<const Case*>& fixed, Technique t, uint32_t size) {
  return find_variant(fixed, configuration_name(t, size));
}

std::string configuration_name(Technique t, uint32_t size) {
  return std::string(names::kTechniques.name(t)) + " " + std::to_string(size);
}

std::string probe_variant() {
  return configuration_name(Technique::kUniform, kQualityProbeSize);
}

double configuration_ms(const Case& c) {
  double ms = 0;
  for (const auto& [pass, t] : c.passes)
    if (!density_pass(pass)) ms += t;
  return ms;
}

double goal_cost_ms(const Case& goal, const std::vector<const Case*>& fixed, bool measures) {
  if (!goal.quality) return configuration_ms(goal);
  const Case* picked = fixed_run(fixed, goal.quality->technique, goal.quality->size);
  const Case* probe = find_variant(fixed, probe_variant());
  if (!picked || !probe) return configuration_ms(goal);
  const auto taken = [&](const std::string& pass) {  // a step the goal took from its probe
    return std::any_of(goal.reused.begin(), goal.reused.end(), [&](const std::string& step) {
      return pass == step || pass.rfind(step + ".", 0) == 0;
    });
  };
  const std::string probe_prefix = "quality_probe.";
  double ms = 0;
  if (measures)  // what only the probe does: the boundary count, depth range, loads
    for (const auto& [pass, t] : goal.passes)
      if (pass.rfind(probe_prefix, 0) == 0 &&
          !probe->passes.count(pass.substr(probe_prefix.size())))
        ms += t;
  for (const auto& [pass, t] : probe->passes)  // the probe's map and hard test
    if (pass.rfind("shadow_map", 0) == 0 || pass.rfind("visibility", 0) == 0) ms += t;
  for (const auto& [pass, t] : picked->passes)
    if (!density_pass(pass) && !taken(pass)) ms += t;
  return ms;
}

double own_rate(const Case& c) {
  return c.error.misclassified_rate();
}

std::optional<Case> with_measured_errors(const Case& goal, const std::vector<const Case*>& fixed,
                                         const RateOf& rate) {
  if (!goal.quality || goal.quality->candidates.empty()) return std::nullopt;
  std::vector<QualityCandidate> known = goal.quality->candidates;
  for (QualityCandidate& c : known)
    if (const Case* f = fixed_run(fixed, c.technique, c.size)) c.predicted_error = rate(*f);
  const QualityCandidate& chosen = choose_candidate(known, goal.goal);
  if (!chosen.raster_load_priced) return std::nullopt;
  return as_picked(goal, chosen.technique, chosen.size);
}

Case as_picked(const Case& goal, Technique technique, uint32_t size) {
  Case pick = goal;
  if (!pick.quality) pick.quality.emplace();
  pick.quality->technique = technique;
  pick.quality->size = size;
  pick.reused.clear();
  // The sweep's views have one light and the hard filter: a pick of the probe's own map takes
  // its map and hard test (engine/choose/quality_pick.hpp, taken_from_probe).
  if (technique == Technique::kUniform && size == kQualityProbeSize)
    pick.reused = {"shadow_map", "visibility.shadow_test"};
  return pick;
}

const Case* cheapest_meeting(double bound, const std::vector<const Case*>& fixed,
                             const RateOf& rate) {
  const Case* best = nullptr;
  for (const Case* f : fixed)
    if (rate(*f) <= bound && (!best || configuration_ms(*f) < configuration_ms(*best))) best = f;
  return best;
}

std::map<std::string, std::vector<const Case*>> fixed_by_view(const std::vector<Case>& cases) {
  std::map<std::string, std::vector<const Case*>> fixed;
  for (const Case& c : cases)
    if (is_fixed_configuration(c.variant)) fixed[c.scene + "/" + c.view].push_back(&c);
  return fixed;
}

bool within_cost(double goal_ms, const Case& cheapest) {
  return goal_ms / configuration_ms(cheapest) <= kCostRatio;
}

void write_quality_section(const std::vector<Case>& cases, const std::vector<FrameError>& frames,
                           std::ostream& md) {
  std::map<std::string, std::vector<const Case*>> fixed = fixed_by_view(cases);
  std::vector<const Case*> goals;
  for (const Case& c : cases)
    if (c.goal.goal != Quality::Goal::kNone && c.quality) goals.push_back(&c);
  if (goals.empty()) return;
  md << "\n## Quality goals: predicted against measured\n\n"
        "Each goal's pick (RenderHeader.quality) with its predicted misclassified rate and "
        "device time beside the measured ones. For max_error, `best fixed` is the cheapest "
        "fixed variant of this sweep (uniform, psm, lispsm, auto at their sizes) measured to "
        "meet the bound on the view, and `ratio` the goal's cost over its cost. A cost is device "
        "time without the bench's own texel-density pass, which a goal's user would not ask for; "
        "a goal's is summed from the fixed variants' measurements of the same work, so that it "
        "carries no second sample of the machine's noise: the configuration it picked, less "
        "the steps it took from its probe, plus the probe's map and hard test as `uniform 512` "
        "measured them, plus what only the probe does (its boundary count, as the goal "
        "measured it). For max_device_ms, `best fixed` is the most accurate fixed variant measured "
        "within the budget. Boundary: "
        "the share of the seen pixels on a shadow edge a map can misplace (on one lit surface: "
        "oracle::boundary_share), as the goal's probe measured it "
        "(uniform 512; the worst light's) and in the ray-traced reference.\n\n"
        "| scene | view | goal | pick | predicted misclass. | measured | predicted ms | "
        "measured device ms | met | best fixed for the goal | its misclass. | cost ms: goal / it | "
        "ratio | "
        "boundary: probe | reference |\n"
        "|---|---|---|---|---:|---:|---:|---:|:---:|---|---:|---:|---:|---:|---:|\n";
  struct Tally {
    int views = 0, met = 0, reachable = 0, met_reachable = 0, comparable = 0, within = 0;
    int known_within = 0;    // with_measured_errors' pick: met and within 1.5x
    int known_unpriced = 0;  // ... that picks a candidate whose time is a lower bound
  };
  // A goal judged with the rates `rate` gives: whether it met its bound, the fixed variant it is
  // judged against (the cheapest that met an error bound, the most accurate within a budget),
  // its cost and ratio, into `t`.
  struct Judged {
    bool met = false;
    const Case* best = nullptr;
    double cost = 0, ratio = NAN;
  };
  const auto judge = [&](const Case& g, const RateOf& rate, Tally& t) {
    const bool by_error = g.goal.goal == Quality::Goal::kMaxError;
    const std::vector<const Case*>& view_fixed = fixed[g.scene + "/" + g.view];
    Judged j;
    j.met = by_error ? rate(g) <= g.goal.value : g.device_ms <= g.goal.value;
    if (by_error)
      j.best = cheapest_meeting(g.goal.value, view_fixed, rate);
    else
      for (const Case* f : view_fixed)
        if (f->device_ms <= g.goal.value && (!j.best || rate(*f) < rate(*j.best))) j.best = f;
    ++t.views, t.met += j.met;
    if (by_error && j.best) ++t.reachable, t.met_reachable += j.met;
    j.cost = goal_cost_ms(g, view_fixed);
    if (by_error && j.best) {
      j.ratio = j.cost / configuration_ms(*j.best);
      ++t.comparable, t.within += j.met && within_cost(j.cost, *j.best);
      if (const std::optional<Case> known = with_measured_errors(g, view_fixed, rate)) {
        // The known pick's own fixed run, for its error.
        const Case* ran = fixed_run(view_fixed, known->quality->technique, known->quality->size);
        t.known_within += ran && rate(*ran) <= g.goal.value &&
                          within_cost(goal_cost_ms(*known, view_fixed), *j.best);
      } else if (g.quality && !g.quality->candidates.empty()) {
        ++t.known_unpriced;
      }
    }
    return j;
  };
  // The views the known errors' replay could not judge, if any.
  const auto unpriced = [](const Tally& t) {
    return t.known_unpriced == 0
               ? std::string()
               : "; on " + std::to_string(t.known_unpriced) +
                     " more it would pick a candidate whose raster load the goal did not "
                     "measure, whose time is unknown";
  };
  std::map<std::string, Tally> tally, over_frames;  // by variant
  const RateOf frame_mean = frame_mean_rate(frames);
  char line[1024];
  for (const Case* g : goals) {
    const Judged j = judge(*g, own_rate, tally[g->variant]);
    if (!frames.empty() && g->goal.goal == Quality::Goal::kMaxError)
      judge(*g, frame_mean, over_frames[g->variant]);
    // The best fixed variant's columns: name, misclassified, costs, ratio (empty where none).
    char fixed_columns[256] = "(none) |  |  | ";
    if (j.best)
      std::snprintf(fixed_columns, sizeof fixed_columns, "%s | %.3f%% | %.1f / %.1f | ",
                    j.best->variant.c_str(), 100 * j.best->error.misclassified_rate(), j.cost,
                    configuration_ms(*j.best));
    char ratio_column[32] = "";
    if (!std::isnan(j.ratio)) std::snprintf(ratio_column, sizeof ratio_column, "%.2fx", j.ratio);
    const std::string technique(names::kTechniques.name(g->quality->technique));
    double probe = 0;
    for (double share : g->quality->boundary_share) probe = std::max(probe, share);
    std::snprintf(line, sizeof line,
                  "| %s | %s | %s | %s %u | %.3f%% | %.3f%% | %.0f | %.1f | %s | %s%s | %.2f%% | "
                  "%.2f%% |\n",
                  g->scene.c_str(), g->view.c_str(), g->variant.c_str(), technique.c_str(),
                  g->quality->size, 100 * g->quality->predicted_error,
                  100 * g->error.misclassified_rate(), g->quality->predicted_device_ms,
                  g->device_ms, j.met ? "yes" : "no", fixed_columns, ratio_column, 100 * probe,
                  100 * g->reference_boundary);
    md << line;
  }
  md << '\n';
  for (const auto& [variant, t] : tally) {
    md << "- `" << variant << "`: met on " << t.met << " of " << t.views << " views";
    if (t.reachable > 0)
      md << " (" << t.met_reachable << " of the " << t.reachable
         << " where a fixed variant met it)";
    if (t.comparable > 0)
      md << "; met within 1.5x the cost of the cheapest fixed variant that met it on " << t.within
         << " of " << t.comparable << " (" << t.known_within
         << " had each candidate's error been known: its measured error in place of the "
            "prediction, the same rule and predicted times"
         << unpriced(t) << ")";
    md << ".\n";
  }
  if (over_frames.empty()) return;
  md << "\nThe error goals again, every rate (the goal's, the fixed variants', the known errors') "
        "the mean over the view and its four nudged frames (the light turned "
     << kNudgeDeg << "°; costs as above):\n\n";
  for (const auto& [variant, t] : over_frames)
    md << "- `" << variant << "`: met on " << t.met << " of " << t.views << " views ("
       << t.met_reachable << " of the " << t.reachable << " where a fixed variant met it); within "
       << "1.5x on " << t.within << " of " << t.comparable << " (" << t.known_within
       << " had each candidate's error been known" << unpriced(t) << ").\n";
}

}  // namespace shadow::bench
