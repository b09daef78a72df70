#include "physgrad/run/pages/learning_verdict.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>

#include "physgrad/catalogue.hpp"
#include "physgrad/report/significant.hpp"
#include "physgrad/run/cases/learning_runs.hpp"

namespace physgrad::run {

namespace {

// The verdict's first words when no rule can be ranked.
constexpr const char* kNoRule = "No rule";

// The level as value_text prints it: rounded up to three significant digits, so that every run
// whose final value set the level still reaches it and each bracket is that of the printed
// number, not of a digit the sentence does not show.
double printed_level(double level) {
  if (!(level > 0) || !std::isfinite(level)) return level;
  const double unit = std::pow(10, std::floor(std::log10(level)) - 2);
  return std::ceil(level / unit * (1 - 1e-12)) * unit;
}

// Where one run crossed the verdict's level, on one axis.
using RunCrossing = std::function<Crossing(const LearningResult&)>;

// Over updates, and over training seconds.
RunCrossing in_updates(double level, const std::function<double(const TrainingRecord&)>& value) {
  return [=](const LearningResult& run) { return updates_crossing(run.summary, level, value); };
}
RunCrossing in_seconds(double level, const std::function<double(const TrainingRecord&)>& value) {
  return [=](const LearningResult& run) { return seconds_crossing(run.summary, level, value); };
}

// Over Adam-update equivalents: the run's updates, each of its rule's (a twin's after its switch)
// counted at the run's cost in Adam updates (adam_updates_per_update), Adam's own as one.
RunCrossing in_adam_updates(double level,
                            const std::function<double(const TrainingRecord&)>& value) {
  return [=](const LearningResult& run) {
    const Crossing u = updates_crossing(run.summary, level, value);
    const double cost = adam_updates_per_update(run);
    const double from = run.params.is_object() ? run.params.value("pretrain_iterations", 0.0) : 0;
    const auto equivalents = [&](double x) { return x <= from ? x : from + (x - from) * cost; };
    // Whole updates, the bracket widened to them.
    return Crossing{std::floor(equivalents(u.low)), std::ceil(equivalents(u.high)),
                    std::round(equivalents(u.estimate))};
  };
}

// The median over the credited runs of `group` of where each crossed.
Crossing group_crossing(const std::vector<const LearningResult*>& group,
                        const RunCrossing& crossing) {
  std::vector<Crossing> crossings;
  for (const LearningResult* run : group) {
    if (credited(*run)) crossings.push_back(crossing(*run));
  }
  return median_crossing(crossings);
}

// Where a rule's values lie over its seeds.
struct SeedRange {
  double low = NAN, high = NAN;
};

// Whether two ranges are apart: one ends below where the other starts.
bool separated(const SeedRange& a, const SeedRange& b) { return a.high < b.low || b.high < a.low; }

SeedRange finals_range(const RuleStanding& s) { return {s.finals.low, s.finals.high}; }

// Whether two rules' finals over several seeds overlap (one seed each: never).
bool finals_not_separated(const RuleStanding& a, const RuleStanding& b) {
  return std::max(a.credited, b.credited) > 1 && !separated(finals_range(a), finals_range(b));
}

// How much lower the median final of `low` lies than that of `high`: "5× " (the digits their
// spreads support; put before "below" or "above"), "" where `low`'s is not positive, and no value
// where the two are within 10 % (about equal).
std::optional<std::string> times_lower(const RuleStanding& low, const RuleStanding& high) {
  if (!(low.final_value > 0)) return std::string();
  if (high.final_value / low.final_value < 1.1) return std::nullopt;
  return physgrad::ratio_text(high.finals, low.finals) + "× ";
}

// "3 seeds", "3 and 2 seeds" (the credited runs of two rules), "one seed".
std::string seeds_text(int a, int b) {
  if (a <= 1 && b <= 1) return "one seed";
  return (a == b ? std::to_string(a) : std::to_string(a) + " and " + std::to_string(b)) + " seeds";
}

// "0.028–0.035", or the one value when the range has no width.
std::string range_text(double low, double high) {
  return low == high ? value_text(low) : value_text(low) + "–" + value_text(high);
}

// The range over the credited seeds of `group` of where each crossed: from the lowest bracket end
// to the highest (high = ∞ when a seed never got there).
SeedRange crossing_range(const std::vector<const LearningResult*>& group,
                         const RunCrossing& crossing) {
  SeedRange range{INFINITY, -INFINITY};
  for (const LearningResult* run : group) {
    if (!credited(*run)) continue;
    const Crossing c = crossing(*run);
    range.low = std::min(range.low, c.reached() ? c.low : INFINITY);
    range.high = std::max(range.high, c.reached() ? c.high : INFINITY);
  }
  return range;
}

// "250–300 vs 9000–11000": where two rules' seeds crossed, from the lowest bracket end to the
// highest; "never" where no seed got there, "from 250 to never" where some did not.
std::string crossing_ranges_text(const SeedRange& a, const SeedRange& b) {
  // Counts in full ("18300"), seconds with three digits.
  const auto number = [](double v) { return with_digits(v, 3); };
  const auto one = [&number](const SeedRange& r) {
    if (!std::isfinite(r.low)) return std::string("never");
    if (!std::isfinite(r.high)) return "from " + number(r.low) + " to never";
    return r.low == r.high ? number(r.low) : number(r.low) + "–" + number(r.high);
  };
  return one(a) + " vs " + one(b);
}

// "280 updates, Adam 10000 (34–38× fewer)": where `rule` and `base` crossed on one axis (the
// brackets between the evaluations that straddle the level, crossing_text), `unit` after the
// rule's count, with the ratio range the brackets allow; over several seeds the medians, the
// seeds' brackets and "not separated" where their ranges overlap.
std::string counts_against(const RuleStanding& rule, const std::vector<const LearningResult*>& runs,
                           const RuleStanding& base,
                           const std::vector<const LearningResult*>& base_runs,
                           const RunCrossing& crossing, const std::string& unit) {
  const Crossing a = group_crossing(runs, crossing), b = group_crossing(base_runs, crossing);
  const int seeds = std::max(rule.credited, base.credited);
  const SeedRange s_rule = crossing_range(runs, crossing);
  const SeedRange s_base = crossing_range(base_runs, crossing);
  const std::string over = seeds_text(rule.credited, base.credited);
  const std::string comparison =
      seeds > 1 && !separated(s_rule, s_base)
          ? "not separated over " + over + "; medians"
          : advantage_text(ratio_range(b, a), "fewer", "more", "about as many",
                           "the brackets do not tell which needs fewer") +
                (seeds > 1 ? "; medians over " + over : "");
  return crossing_text(a) + unit + ", " + base.label + " " + crossing_text(b) + " (" + comparison +
         (seeds > 1 ? ", the seeds' brackets spanning " + crossing_ranges_text(s_rule, s_base)
                    : "") +
         ")";
}

// "; its update costs 3.7 Adam updates (timed beside its steps)", from the cost probes; without
// them the ratio of the two runs' seconds per update, which machine load can bias, says so.
std::string cost_text(const RuleStanding& rule, const RuleStanding& base) {
  if (rule.control) return {};  // an Adam update, by definition
  const std::string whose = "; its update" + std::string(rule.twin ? " after the switch" : "");
  if (std::isfinite(rule.adam_updates) && rule.adam_updates > 0) {
    return whose + " costs " + with_digits(rule.adam_updates, 2) + " " + base.label +
           " updates (timed beside its steps)";
  }
  const double m = rule.seconds_per_update / base.seconds_per_update;
  if (!(std::isfinite(m) && m > 0)) return {};
  return whose + " costs " + ratio_text(m) + " " + base.label + "'s (seconds per update of the " +
         "two runs)";
}

// "; in wall time (measured at the same evaluations) HIG gets there 9–11× sooner (0.07 vs
// 0.72 s)", or that the seeds do not separate them; empty when either never got there.
std::string wall_time_text(const RuleStanding& rule, const std::vector<const LearningResult*>& runs,
                           const RuleStanding& base,
                           const std::vector<const LearningResult*>& base_runs,
                           const RunCrossing& crossing) {
  const Crossing t_rule = group_crossing(runs, crossing);
  const Crossing t_base = group_crossing(base_runs, crossing);
  if (!t_rule.reached() || !t_base.reached()) return {};
  const RatioRange sooner = ratio_range(t_base, t_rule);
  const bool rule_sooner = sooner.low >= 1.1, base_sooner = sooner.high <= 1 / 1.1;
  const bool apart = std::max(rule.credited, base.credited) < 2 ||
                     separated(crossing_range(runs, crossing), crossing_range(base_runs, crossing));
  std::string out = "; in wall time (measured at the same evaluations) ";
  out += !apart ? "they are not separated over " + seeds_text(rule.credited, base.credited)
         : rule_sooner || base_sooner
             ? (rule_sooner ? rule.label : base.label) + " gets there " +
                   advantage_text(sooner, "sooner", "sooner", "", "")
             : advantage_text(sooner, "", "", "both get there about together",
                              "the brackets do not tell which gets there sooner");
  return out + " (" + crossing_text(t_rule) + " vs " + crossing_text(t_base) + " s)";
}

// "to reach 0.1 HIG needs 280 updates, Adam 10000 (34–38× fewer); its update costs 3.7 Adam
// updates (timed beside its steps); in Adam-update equivalents 1000, Adam 10000 (9–11× fewer); in
// wall time (measured at the same evaluations) HIG gets there 9–11× sooner (0.07 vs 0.72 s)",
// `rule` against `base` (Adam). Every count and ratio carries no digit finer than the brackets.
std::string against_adam(const RuleStanding& rule, const std::vector<const LearningResult*>& runs,
                         const RuleStanding& base,
                         const std::vector<const LearningResult*>& base_runs,
                         const VerdictInput& input) {
  const double level = printed_level(std::max(rule.reach_level, base.reach_level));
  std::string out = "to reach " + value_text(level) + " " + rule.label + " needs " +
                    counts_against(rule, runs, base, base_runs, in_updates(level, input.value),
                                   " updates") +
                    cost_text(rule, base);
  if (std::isfinite(rule.adam_updates) && !rule.control) {
    out += "; in " + base.label + "-update equivalents " +
           counts_against(rule, runs, base, base_runs, in_adam_updates(level, input.value), "");
  }
  return out + wall_time_text(rule, runs, base, base_runs, in_seconds(level, input.value));
}

// A rule's final value alone: "0.5 (one seed)", "0.5 (range 0.4–0.6 over 3 seeds)".
std::string finals_text(const RuleStanding& s) {
  if (s.credited <= 1) return value_text(s.final_value) + " (one seed)";
  return value_text(s.final_value) + " (range " + range_text(s.finals.low, s.finals.high) +
         " over " + seeds_text(s.credited, s.credited) + ")";
}

// The lowest two rules compared: "HIG's final test loss is 5× below Adam's (0.02 vs 0.1, one
// seed)"; over several seeds with the medians and ranges, and "HIG's and Adam's final test loss
// are not separated over 3 seeds (…)" where the two ranges overlap.
std::string ranking_text(const RuleStanding& best, const RuleStanding& next,
                         const std::string& what) {
  const int seeds = std::max(best.credited, next.credited);
  const std::string over = seeds_text(best.credited, next.credited);
  const std::string values =
      seeds > 1 ? "medians " + value_text(best.final_value) + " vs " +
                      value_text(next.final_value) + ", ranges " +
                      range_text(best.finals.low, best.finals.high) + " vs " +
                      range_text(next.finals.low, next.finals.high) + " over " + over
                : value_text(best.final_value) + " vs " + value_text(next.final_value) + ", " +
                      over;
  if (finals_not_separated(best, next)) {
    return best.label + "'s and " + next.label + "'s " + what + " are not separated over " +
           over + " (" + values + ")";
  }
  const std::optional<std::string> times = times_lower(best, next);
  return best.label + "'s " + what + " is " +
         (times ? *times + "below " : "about equal to ") + next.label + "'s (" + values + ")";
}

// " After the same switch, Adam→HIG ends 1.3× below the control Adam→Adam (lr ×0.1) (0.05 vs
// 0.065); …": each ranked twin's median final value against the ranked control's, the ratio with
// the digits their spreads support, or "not separated over 3 seeds" where their seeds' ranges
// overlap; empty without a ranked control or twin.
std::string against_control(const std::vector<RuleStanding>& all,
                            const std::vector<std::size_t>& ranked) {
  const auto control =
      std::find_if(ranked.begin(), ranked.end(), [&](std::size_t k) { return all[k].control; });
  if (control == ranked.end()) return {};
  const RuleStanding& c = all[*control];
  std::string out;
  for (const std::size_t k : ranked) {
    const RuleStanding& twin = all[k];
    if (!twin.twin || twin.control) continue;
    out += out.empty() ? "" : "; ";
    if (finals_not_separated(twin, c)) {
      out += twin.label + " and the control " + c.label + " are not separated over " +
             seeds_text(twin.credited, c.credited) + " (medians " + value_text(twin.final_value) +
             " vs " + value_text(c.final_value) + ")";
      continue;
    }
    const bool below = twin.final_value <= c.final_value;
    const std::optional<std::string> times = below ? times_lower(twin, c) : times_lower(c, twin);
    out += twin.label + " ends " +
           (times ? *times + (below ? "below" : "above") : std::string("about as low as")) +
           " the control " + c.label + " (" + value_text(twin.final_value) + " vs " +
           value_text(c.final_value) + ")";
  }
  return out.empty() ? std::string() : " After the same switch, " + out + ".";
}

}  // namespace

bool credited(const LearningResult& run) {
  const std::optional<TrainingTermination>& end = run.summary.termination;
  const bool switched = !run.params.contains("switched") || run.params.at("switched") == true;
  return end && ended_by_limit(*end) && switched;
}

RuleStanding standing(const std::vector<const LearningResult*>& group,
                      const std::function<double(const TrainingRecord&)>& value) {
  RuleStanding s;
  s.id = group.front()->id;
  s.label = run_rule_label(s.id, group.front()->params);
  s.control = is_control_run(s.id);
  std::vector<double> finals, costs, adam_updates;
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
    s.twin = s.twin || run->params.contains("pretrain_iterations");
    const double cost = rule_seconds_per_update(*run);
    if (std::isfinite(cost)) costs.push_back(cost);
    adam_updates.push_back(adam_updates_per_update(*run));
  }
  s.final_value = median(finals);
  s.finals = spread_of(finals);
  if (!finals.empty()) {
    std::vector<double> sorted = finals;
    std::sort(sorted.begin(), sorted.end(), [](double a, double b) {
      return std::isnan(b) ? !std::isnan(a) : (!std::isnan(a) && a < b);
    });
    s.reach_level = sorted[sorted.size() / 2];
  }
  s.seconds_per_update = median(costs);
  const bool probed = std::all_of(adam_updates.begin(), adam_updates.end(),
                                  [](double c) { return std::isfinite(c); });
  if (probed) s.adam_updates = median(adam_updates);
  return s;
}

std::string verdict_after(const std::string& lead, std::string sentence) {
  if (sentence.rfind(kNoRule, 0) == 0) sentence[0] = 'n';
  return lead + sentence;
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
    return std::string(kNoRule) + " ended a run within its limits with a finite " + input.what +
           ".";
  }
  const RuleStanding& best = all[ranked.front()];
  std::string out = ranked.size() == 1
                        ? best.label + "'s " + input.what + " is " + finals_text(best)
                        : ranking_text(best, all[ranked[1]], input.what);
  for (std::size_t k = 2; k < ranked.size(); ++k) {
    const RuleStanding& s = all[ranked[k]];
    const RuleStanding& above = all[ranked[k - 1]];
    out += "; " + s.label + "'s is " + finals_text(s);
    if (finals_not_separated(s, above)) out += ", not separated from " + above.label + "'s";
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
  out += against_control(all, ranked);
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
