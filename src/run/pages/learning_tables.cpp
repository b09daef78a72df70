// LearningSweep's tables: final test losses per seed with median and worst, the saturated-neuron
// fraction, the time split per step of every rule, and where each pretrained run switched.
#include <algorithm>
#include <cmath>

#include "physgrad/run/cases/learning_runs.hpp"
#include "physgrad/run/pages/learning_verdict.hpp"
#include "physgrad/report/significant.hpp"

namespace physgrad::run {

namespace {

using SweepResults = std::deque<LearningResult>;

double final_test_loss(const LearningResult& r) { return r.summary.history.back().test_loss; }

std::string milliseconds(double seconds, long long steps) {
  return steps > 0 ? format_value(1e3 * seconds / static_cast<double>(steps)) : "–";
}

// The settings, rules and seeds of a sweep's runs, each in the order first run.
struct SweepAxes {
  std::vector<std::string> tags, ids;
  std::vector<long long> seeds;
};

SweepAxes sweep_axes(const SweepResults& results) {
  SweepAxes axes;
  for (const LearningResult& r : results) {
    if (std::find(axes.tags.begin(), axes.tags.end(), r.tag) == axes.tags.end()) {
      axes.tags.push_back(r.tag);
    }
    if (std::find(axes.ids.begin(), axes.ids.end(), r.id) == axes.ids.end()) {
      axes.ids.push_back(r.id);
    }
    if (std::find(axes.seeds.begin(), axes.seeds.end(), r.seed) == axes.seeds.end()) {
      axes.seeds.push_back(r.seed);
    }
  }
  return axes;
}

const LearningResult* find_sweep_result(const SweepResults& results, const std::string& tag,
                                        const std::string& id, long long seed) {
  const auto it = std::find_if(results.begin(), results.end(), [&](const LearningResult& r) {
    return r.tag == tag && r.id == id && r.seed == seed;
  });
  return it == results.end() ? nullptr : &*it;
}

// The final-loss table of one setting (a row per rule: per seed, median, worst) and the
// saturation table beside it (filled when the runs record the saturated fraction).
struct FinalLossTables {
  RunContext::Table losses, saturation;
  std::vector<double> medians;
  std::vector<Spread> spreads;  // the digits of a row and of its ratio follow its spread
};

FinalLossTables empty_final_loss_tables(const std::string& tag,
                                        const std::vector<long long>& seeds) {
  FinalLossTables t{{"Final test loss per seed (" + tag +
                         "): the mean loss over the test set after the last iteration, "
                         "with the median and the worst over the seeds",
                     {"rule"}, {}},
                    {"Saturated hidden neurons at the end, per seed (" + tag +
                         "): the fraction (0 to 1) of hidden neurons with |tanh| > "
                         "0.99 on every test input",
                     {"rule"}, {}},
                    {}, {}};
  for (const long long seed : seeds) {
    t.losses.header.push_back("seed " + std::to_string(seed));
    t.saturation.header.push_back("seed " + std::to_string(seed));
  }
  t.losses.header.insert(t.losses.header.end(), {"median", "worst", "median / lowest"});
  return t;
}

// The rows of rule `id` at setting `tag`.
void add_final_loss_rows(FinalLossTables& t, const SweepResults& results, const SweepAxes& axes,
                         const std::string& tag, const std::string& id, bool has_saturation) {
  // A pretrained run none of whose seeds switched is Adam's, and reads so.
  bool switched = pretrained_rule(id).empty();
  nlohmann::json params;  // of a run of the rule, which name its step (the control's)
  for (const long long seed : axes.seeds) {
    const LearningResult* r = find_sweep_result(results, tag, id, seed);
    switched = switched || (r != nullptr && r->params.value("switched", false));
    if (r != nullptr && params.is_null()) params = r->params;
  }
  const std::string label = switched ? run_rule_label(id, params)
                                     : learning_run_label(kPretrainingRule) +
                                           " (never switched to " +
                                           taking_over_label(id, params) + ")";
  std::vector<std::string> row = {label}, saturated = {label};
  // A run that failed, diverged or never switched is shown, never counted in a median.
  std::vector<double> values;
  for (const long long seed : axes.seeds) {
    const LearningResult* r = find_sweep_result(results, tag, id, seed);
    if (r != nullptr && credited(*r)) values.push_back(final_test_loss(*r));
  }
  t.spreads.push_back(spread_of(values));
  const auto shown = [&](double v) { return with_digits(v, digits_for(t.spreads.back())); };
  for (const long long seed : axes.seeds) {
    const LearningResult* r = find_sweep_result(results, tag, id, seed);
    if (r == nullptr) {
      row.push_back("–");
      saturated.push_back("–");
      continue;
    }
    row.push_back(shown(final_test_loss(*r)) +
                  (credited(*r)                                ? std::string()
                   : r->params.value("switched", true) == false ? " (never switched)"
                                                : " (" + to_string(*r->summary.termination) + ")"));
    if (has_saturation) {
      saturated.push_back(format_value(r->summary.history.back().extras["saturated_fraction"]));
    }
  }
  t.medians.push_back(median(values));
  row.push_back(shown(t.medians.back()));
  row.push_back(values.empty() ? "–" : shown(*std::max_element(values.begin(), values.end())));
  t.losses.rows.push_back(std::move(row));
  t.saturation.rows.push_back(std::move(saturated));
}

// The last column: the lowest finite median (best), every other as a multiple of it with the
// digits their spreads support.
void mark_lowest_median(FinalLossTables& t) {
  double lowest = INFINITY;
  for (const double m : t.medians) {
    if (std::isfinite(m)) lowest = std::min(lowest, m);
  }
  const auto multiple = [&](std::size_t k) {
    const auto best = std::find(t.medians.begin(), t.medians.end(), lowest) - t.medians.begin();
    return with_digits(t.medians[k] / lowest, ratio_digits(t.spreads[k], t.spreads[best]));
  };
  for (std::size_t k = 0; k < t.losses.rows.size(); ++k) {
    t.losses.rows[k].push_back(!std::isfinite(t.medians[k]) ? "–"
                               : t.medians[k] == lowest     ? "best"
                                                            : "×" + multiple(k));
  }
  t.losses.title += "; the last column marks the lowest median (best) and gives the others as "
                    "multiples of it. A run in brackets (failed, diverged, never switched) counts "
                    "in no median";
}

// The median of the runs' costs in Adam updates with two digits; "–" unless every run has one.
std::string adam_updates_text(const std::vector<double>& costs) {
  const bool all = !costs.empty() && std::all_of(costs.begin(), costs.end(), [](double c) {
    return std::isfinite(c);
  });
  return all ? with_digits(median(costs), 2) : "–";
}

// Time per step of every rule and setting, summed over the seeds; a twin's total also per part
// (phase_costs: its Adam updates, then its rule's).
RunContext::Table step_time_table(const SweepResults& results, const SweepAxes& axes) {
  RunContext::Table timing{"Time per training step in milliseconds, mean over seeds: the "
                           "forward pass of network, physics and loss; the gradient or stacked "
                           "Jacobian; the inversion inside gn/hig; the rest of the update (a "
                           "pretrained run: over its Adam and its rule's steps together); a "
                           "pretrained run's total also per part, its Adam updates before the "
                           "switch and its rule's after it; and the rule's update (a pretrained "
                           "run's after the switch) in Adam updates timed beside its steps in the "
                           "same process, median over seeds, which machine load does not bias",
                           {"rule", "setting", "forward (ms)", "gradient or Jacobian (ms)",
                            "inversion (ms)", "update (ms)", "total (ms)", "Adam part (ms)",
                            "rule part (ms)", "in Adam updates"},
                           {}};
  for (const std::string& tag : axes.tags) {
    for (const std::string& id : axes.ids) {
      TrainingSummary total;
      PhaseCost parts[2];
      std::vector<double> adam_updates;
      nlohmann::json params;
      for (const LearningResult& r : results) {
        if (r.tag != tag || r.id != id) continue;
        if (params.is_null()) params = r.params;
        total.iterations += r.summary.iterations;
        total.forward_seconds += r.summary.forward_seconds;
        total.derivative_seconds += r.summary.derivative_seconds;
        total.inversion_seconds += r.summary.inversion_seconds;
        total.update_seconds += r.summary.update_seconds;
        total.train_seconds += r.summary.train_seconds;
        adam_updates.push_back(adam_updates_per_update(r));
        const std::vector<PhaseCost> phases = phase_costs(r);
        for (std::size_t p = 0; p < phases.size() && p < 2; ++p) {
          parts[p].updates += phases[p].updates;
          parts[p].seconds += phases[p].seconds;
        }
      }
      const long long steps = total.iterations;
      const bool twin = !pretrained_rule(id).empty();
      timing.rows.push_back({run_rule_label(id, params), tag,
                             milliseconds(total.forward_seconds, steps),
                             milliseconds(total.derivative_seconds, steps),
                             milliseconds(total.inversion_seconds, steps),
                             milliseconds(total.update_seconds, steps),
                             milliseconds(total.train_seconds, steps),
                             twin ? milliseconds(parts[0].seconds, parts[0].updates) : "–",
                             twin ? milliseconds(parts[1].seconds, parts[1].updates) : "–",
                             adam_updates_text(adam_updates)});
    }
  }
  return timing;
}

}  // namespace

void LearningSweep::add_tables() const {
  const SweepAxes axes = sweep_axes(results_);
  const bool has_saturation =
      !results_.empty() && results_.front().summary.history.back().extras.contains(
                               "saturated_fraction");
  for (const std::string& tag : axes.tags) {
    FinalLossTables tables = empty_final_loss_tables(tag, axes.seeds);
    for (const std::string& id : axes.ids) {
      add_final_loss_rows(tables, results_, axes, tag, id, has_saturation);
    }
    mark_lowest_median(tables);
    context_.add_table(std::move(tables.losses));
    if (has_saturation) context_.add_table(std::move(tables.saturation));
  }
  context_.add_table(step_time_table(results_, axes));
  add_switch_note();
}

void LearningSweep::add_switch_note() const {
  std::string note, control;
  for (const LearningResult& r : results_) {
    const std::string rule = pretrained_rule(r.id);
    if (rule.empty()) continue;
    if (is_control_run(r.id) && control.empty()) {
      control = run_rule_label(r.id, r.params);
      control += " is the control: the same Adam part, switched where the twins switch, then a "
                 "fresh Adam at " + format_value(r.params.value("control_lr_factor", NAN)) +
                 " × its step, so that what a rule gains after the switch can be told from what "
                 "a smaller step gives. ";
    }
    const std::string who = run_rule_label(r.id, r.params) + " (" + r.tag + ", seed " +
                            std::to_string(r.seed) + ")";
    if (r.params.value("switched", false)) {
      const long long at = r.params.at("pretrain_iterations").get<long long>();
      double seconds = 0;
      for (const TrainingRecord& record : r.summary.history) {
        if (record.iteration <= at) seconds = record.train_seconds;
      }
      note += (note.empty() ? "" : " ") + who + ": Adam made " + std::to_string(at) +
              " updates (" + format_value(seconds) + " s) before " +
              taking_over_label(r.id, r.params) + " took over.";
    } else {
      note += (note.empty() ? "" : " ") + who + " never switched within its budget: it is Adam's "
              "run, shown as such and not ranked.";
    }
  }
  if (note.empty()) return;
  const std::string pretrain = settings_.text("pretrain");
  context_.add_note(
      "The Adam→ runs are the HIG paper's switch from Adam to the rule, " +
      (pretrain == "auto"
           ? "made once Adam's evaluated training loss had levelled off (--pretrain auto: the best "
             "of the last " + std::to_string(settings_.integer("plateau-window")) +
                 " evaluations less than " + format_value(100 * settings_.real("plateau-fraction")) +
                 " % below the best before them)"
           : "after --pretrain " + pretrain + " Adam updates") +
      "; the switch is marked on the curves. " + control + note);
}

}  // namespace physgrad::run
