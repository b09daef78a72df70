#include "physgrad/run/learning_verdict.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "physgrad/catalogue.hpp"
#include "physgrad/run/learning_runs.hpp"

namespace physgrad::run {

namespace {

// Where a run's curve of `value` over `progress` first reaches `level`: between the evaluation
// before and the one at or below it, log-linear in the value (linear where a value is ≤ 0).
double progress_to_reach(const TrainingSummary& run, double level,
                         const std::function<double(const TrainingRecord&)>& value,
                         const std::function<double(const TrainingRecord&)>& progress) {
  const std::vector<TrainingRecord>& h = run.history;
  for (std::size_t k = 0; k < h.size(); ++k) {
    const double v = value(h[k]);
    if (!(v <= level)) continue;
    if (k == 0) return progress(h[0]);
    const double before = value(h[k - 1]);
    double t = 1;
    if (std::isfinite(before) && before > v) {
      const bool logs = v > 0 && level > 0;
      t = logs ? std::log(before / level) / std::log(before / v) : (before - level) / (before - v);
    }
    const double p0 = progress(h[k - 1]), p1 = progress(h[k]);
    return p0 + std::clamp(t, 0.0, 1.0) * (p1 - p0);
  }
  return NAN;
}

// The median of per-run numbers where a run that never got there (NaN) counts as the largest:
// NaN when fewer than half the runs got there.
double median_reached(std::vector<double> values) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end(), [](double a, double b) {
    return std::isnan(b) ? !std::isnan(a) : (!std::isnan(a) && a < b);
  });
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// An update count: whole from 100 on ("10000"), else three significant digits (interpolated
// between evaluations: "6.78").
std::string count_text(double count) {
  if (count >= 100 && count < 1e15) return std::to_string(std::llround(count));
  std::ostringstream out;
  out.precision(3);
  out << count;
  return out.str();
}

// "HIG needs 35× fewer updates (94 vs 3300)" and the wall-time outcome, `rule` against `base`.
std::string against_adam(const RuleStanding& rule, const std::vector<const LearningResult*>& runs,
                         const RuleStanding& base,
                         const std::vector<const LearningResult*>& base_runs,
                         const VerdictInput& input) {
  const double level = std::max(rule.reach_level, base.reach_level);
  const auto reach = [&](const std::vector<const LearningResult*>& group, bool in_seconds) {
    std::vector<double> values;
    for (const LearningResult* run : group) {
      if (!credited(*run)) continue;
      values.push_back(in_seconds ? seconds_to_reach(run->summary, level, input.value)
                                  : updates_to_reach(run->summary, level, input.value));
    }
    return median_reached(std::move(values));
  };
  const double u_rule = reach(runs, false), u_base = reach(base_runs, false);
  const double t_rule = reach(runs, true), t_base = reach(base_runs, true);
  std::string out = "to reach " + value_text(level) + " " + rule.label + " needs ";
  if (!(u_rule > 0) || !(u_base > 0)) {
    out += count_text(u_rule) + " updates, " + base.label + " " + count_text(u_base);
  } else {
    const double n = u_base / u_rule;
    out += n >= 1 ? ratio_text(n) + " fewer updates" : ratio_text(1 / n) + " more updates";
    out += " (" + count_text(u_rule) + " vs " + count_text(u_base) + ")";
  }
  const double m = rule.seconds_per_update / base.seconds_per_update;
  out += "; its update costs " + ratio_text(m) + " " + base.label + "'s";
  if (std::isfinite(t_rule) && std::isfinite(t_base) && t_rule > 0 && t_base > 0) {
    const bool rule_wins = t_rule < t_base;
    const double sooner = rule_wins ? t_base / t_rule : t_rule / t_base;
    out += sooner < 1.1 ? ", so in wall time both get there about together ("
                        : ", so in wall time " + (rule_wins ? rule.label : base.label) +
                              " gets there " + ratio_text(sooner) + " sooner (";
    out += value_text(t_rule) + " vs " + value_text(t_base) + " s)";
  }
  return out;
}

}  // namespace

bool credited(const LearningResult& run) {
  const std::optional<TrainingTermination>& end = run.summary.termination;
  const bool switched = !run.params.contains("switched") || run.params.at("switched") == true;
  return end && ended_by_limit(*end) && switched;
}

double updates_to_reach(const TrainingSummary& run, double level,
                        const std::function<double(const TrainingRecord&)>& value) {
  return progress_to_reach(run, level, value, [](const TrainingRecord& r) {
    return static_cast<double>(r.iteration);
  });
}

double seconds_to_reach(const TrainingSummary& run, double level,
                        const std::function<double(const TrainingRecord&)>& value) {
  return progress_to_reach(run, level, value,
                           [](const TrainingRecord& r) { return r.train_seconds; });
}

RuleStanding standing(const std::vector<const LearningResult*>& group,
                      const std::function<double(const TrainingRecord&)>& value) {
  RuleStanding s;
  s.id = group.front()->id;
  s.label = learning_run_label(s.id);
  std::vector<double> finals, costs;
  for (const LearningResult* run : group) {
    if (run->params.contains("switched") && run->params.at("switched") == false) {
      s.never_switched = true;
      continue;
    }
    if (!credited(*run)) {
      ++s.failed;
      continue;
    }
    ++s.credited;
    const double v = value(run->summary.history.back());
    finals.push_back(std::isfinite(v) ? v : NAN);
    if (run->summary.iterations > 0) {
      costs.push_back(run->summary.train_seconds / static_cast<double>(run->summary.iterations));
    }
  }
  s.final_value = median(finals);
  if (!finals.empty()) {
    std::vector<double> sorted = finals;
    std::sort(sorted.begin(), sorted.end(), [](double a, double b) {
      return std::isnan(b) ? !std::isnan(a) : (!std::isnan(a) && a < b);
    });
    s.reach_level = sorted[sorted.size() / 2];
  }
  s.seconds_per_update = median(costs);
  return s;
}

std::string ratio_text(double ratio) {
  if (!(ratio > 0)) return "–";
  if (!std::isfinite(ratio)) return "∞×";
  const double unit = std::pow(10, std::floor(std::log10(ratio)) - 1);  // of the second digit
  const double rounded = std::round(ratio / unit) * unit;
  std::ostringstream out;
  if (rounded >= 10) {
    out << std::fixed << std::setprecision(0) << rounded;
  } else {
    out.precision(2);
    out << rounded;
  }
  return out.str() + "×";
}

std::string value_text(double value) {
  std::ostringstream out;
  out.precision(3);
  out << value;
  return out.str();
}

std::string verdict_sentence(const VerdictInput& input) {
  std::vector<RuleStanding> all;
  for (const auto& group : input.groups) all.push_back(standing(group, input.value));
  std::vector<std::size_t> ranked;
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (all[k].credited > 0 && std::isfinite(all[k].final_value)) ranked.push_back(k);
  }
  std::sort(ranked.begin(), ranked.end(),
            [&](std::size_t a, std::size_t b) { return all[a].final_value < all[b].final_value; });
  if (ranked.empty()) {
    return "No rule ended a run within its limits with a finite " + input.what + ".";
  }
  const RuleStanding& best = all[ranked.front()];
  std::string out = best.label + "'s " + input.what + " is ";
  if (ranked.size() == 1) {
    out += value_text(best.final_value);
  } else {
    const RuleStanding& next = all[ranked[1]];
    const double ratio = next.final_value / best.final_value;
    out += (best.final_value > 0 && ratio < 1.1 ? "about equal to " + next.label + "'s"
            : best.final_value > 0             ? ratio_text(ratio) + " below " + next.label + "'s"
                                               : "below " + next.label + "'s") +
           " (" + value_text(best.final_value) + " vs " + value_text(next.final_value) + ")";
  }
  for (std::size_t k = 2; k < ranked.size(); ++k) {
    out += "; " + all[ranked[k]].label + "'s is " + value_text(all[ranked[k]].final_value);
  }
  for (const RuleStanding& s : all) {
    if (s.failed > 0) {
      out += "; " + s.label + ": " + std::to_string(s.failed) + " of " +
             std::to_string(s.failed + s.credited) +
             " runs failed or diverged and are not ranked";
    }
    if (s.never_switched) {
      out += "; " + s.label + " never switched from Adam within its budget (shown as Adam, not "
             "ranked)";
    }
  }
  out += ".";
  // Per update and per second, each ranked rule against Adam.
  const auto adam = std::find_if(ranked.begin(), ranked.end(),
                                 [&](std::size_t k) { return all[k].id == kPretrainingRule; });
  if (adam == ranked.end()) return out;
  std::string against;
  for (const std::size_t k : ranked) {
    if (k == *adam) continue;
    against += (against.empty() ? "" : "; ") +
               against_adam(all[k], input.groups[k], all[*adam], input.groups[*adam], input);
  }
  if (!against.empty()) out += " Per update and per second against Adam: " + against + ".";
  return out;
}

}  // namespace physgrad::run
