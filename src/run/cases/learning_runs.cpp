#include "physgrad/run/cases/learning_runs.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <new>

#include "physgrad/run/cases/learning_case.hpp"
#include "physgrad/run/life/checkpoint.hpp"
#include "physgrad/run/cases/learning_experiment.hpp"
#include "physgrad/run/cases/direct_runs.hpp"
#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/io/serialize.hpp"

namespace physgrad::run {

namespace {

// Evaluations by time in a run limited by --time alone: this many over the budget.
constexpr double kEvaluationsOverTime = 40;

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// "45 s", "3 min 20 s", "1 h 5 min".
std::string duration_text(double seconds) {
  const auto s = static_cast<long long>(std::llround(std::max(0.0, seconds)));
  if (s < 60) return std::to_string(s) + " s";
  if (s < 3600) return std::to_string(s / 60) + " min " + std::to_string(s % 60) + " s";
  return std::to_string(s / 3600) + " h " + std::to_string(s % 3600 / 60) + " min";
}

// How much of a run is done, 0 to 1, by the limits it has (the furthest of them); `run_seconds`
// is the wall time this process has spent on the run (what --time bounds, with the evaluations).
double run_fraction(const TrainerOptions& options, const TrainingRecord& r, double run_seconds) {
  double f = 0;
  if (options.time_budget_seconds) f = std::max(f, run_seconds / *options.time_budget_seconds);
  if (options.max_iterations) {
    f = std::max(f, static_cast<double>(r.iteration) / static_cast<double>(*options.max_iterations));
  }
  if (options.max_epochs) f = std::max(f, r.epoch / static_cast<double>(*options.max_epochs));
  return std::clamp(f, 0.0, 1.0);
}

// "run 7/15" (or "run 7" while the count is not known).
std::string run_number(const RunContext::RunPlan& plan) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, falsely) on "run " + a temporary here.
  std::string out = "run ";
  out += std::to_string(plan.finished + 1);
  if (plan.runs > 0) {
    out += '/';
    out += std::to_string(plan.runs);
  }
  return out;
}

// "12 s elapsed, about 3 min 40 s left": the time left extrapolates the wall time per run so far
// (evaluations included) over the runs still to come; `fraction` is the current run's part done.
std::string time_left(const RunContext::RunPlan& plan, double fraction) {
  const double elapsed = steady_seconds() - plan.started;
  const double done = static_cast<double>(plan.finished) + fraction;
  std::string out = duration_text(elapsed) + " elapsed";
  if (plan.runs > 0 && done > 0.02) {
    out += ", about " +
           duration_text(elapsed / done * std::max(0.0, static_cast<double>(plan.runs) - done)) +
           " left";
  }
  return out;
}

// The progress lines of one run: one per evaluation, and one when it finished (a run taken whole
// from the checkpoint reports nothing).
class SweepRunProgress {
 public:
  SweepRunProgress(RunContext& context, const TrainerOptions& options)
      : context_(context),
        plan_(context.run_plan()),
        name_(context.experiment_name() + ": " + run_number(plan_) + ", "),
        budget_(options.time_budget_seconds
                    ? " s of training, the run's budget " +
                          format_value(*options.time_budget_seconds)
                    : "") {}

  void evaluated(const LearningResult& result, const TrainerOptions& options,
                 const TrainingRecord& r) {
    trained_now_ = true;
    if (!plan_.announcement.empty()) {
      context_.progress_event(plan_.announcement);
      plan_.announcement.clear();
    }
    context_.progress(name_ + result.label + " seed " + std::to_string(result.seed) +
                      ", iteration " + std::to_string(r.iteration) + ", test loss " +
                      format_value(r.test_loss) + " · " + format_value(r.train_seconds) +
                      budget_ + " s · " +
                      time_left(plan_, run_fraction(options, r, steady_seconds() - started_)));
  }

  void finished(const LearningResult& result) const {
    if (!trained_now_) return;
    context_.progress_event(name_ + result.label + " seed " + std::to_string(result.seed) +
                            " finished: " + std::to_string(result.summary.iterations) +
                            " iterations in " + format_value(result.summary.train_seconds) +
                            " s of training, test loss " +
                            format_value(result.summary.history.back().test_loss) + " · " +
                            time_left(plan_, 0));
  }

 private:
  RunContext& context_;
  RunContext::RunPlan& plan_;
  const std::string name_, budget_;
  const double started_ = steady_seconds();
  bool trained_now_ = false;
};

}  // namespace

LearningSweep::LearningSweep(const Settings& settings, RunContext& context,
                             std::map<std::string, RuleDefaults> defaults)
    : settings_(settings), context_(context), defaults_(std::move(defaults)) {
  // The first sweep of the experiment plans its runs: seeds × every list setting (the rules and
  // sweeps such as ξ or λ); without --optimizers the experiment gives its rule count.
  RunContext::RunPlan& plan = context_.run_plan();
  if (plan.started >= 0) return;
  plan.started = steady_seconds();
  if (settings_.has("optimizers")) plan_runs(settings_.texts("optimizers"));
  if (settings_.has("pretrain") && settings_.text("pretrain") != "0" && !switch_condition()) {
    context_.add_note("No run is pretrained with Adam: --pretrain " + settings_.text("pretrain") +
                      " would leave none of the --iters " +
                      std::to_string(settings_.integer("iters")) + " to the rule taking over.");
  }
}

LearningSweep::LearningSweep(const Settings& settings, RunContext& context,
                             const LearningCase& learning_case)
    : LearningSweep(settings, context, learning_case.defaults) {
  draw_from(learning_case.samples);
}

std::optional<SwitchCondition> LearningSweep::switch_condition() const {
  if (!settings_.has("pretrain")) return std::nullopt;
  const std::string text = settings_.text("pretrain");
  SwitchCondition condition;
  if (text == "auto") {
    condition.window = static_cast<int>(settings_.integer("plateau-window"));
    condition.fraction = settings_.real("plateau-fraction");
    return condition;
  }
  condition.after = pretrain_iterations(text);
  if (condition.after == 0 || (settings_.has("iters") && condition.after >= settings_.integer("iters"))) {
    return std::nullopt;
  }
  return condition;
}

std::vector<std::string> LearningSweep::run_ids(const std::vector<std::string>& rules) const {
  std::vector<std::string> ids;
  bool twins = false;
  for (const std::string& id : rules) {
    const bool twin =
        switch_condition() && make_learning_update(id)->need() == UpdateNeed::kStackedJacobian;
    if (!twin || rules_alone()) ids.push_back(id);
    if (twin) ids.push_back(pretrained_run_id(id));
    twins = twins || twin;
  }
  // The control arm, once beside the twins.
  if (twins && control_factor()) ids.push_back(pretrained_run_id(kPretrainingRule));
  return ids;
}

void LearningSweep::plan_runs(const std::vector<std::string>& rules) {
  RunContext::RunPlan& plan = context_.run_plan();
  if (plan.runs > 0) return;
  long long runs = settings_.has("seeds") ? settings_.integer("seeds") : 1;
  for (const auto& [name, value] : settings_.json().items()) {
    if (value.is_array() && name != "optimizers") runs *= static_cast<long long>(value.size());
  }
  plan.runs = runs * static_cast<long long>(run_ids(rules).size());
  std::string line = context_.experiment_name() + ": " + std::to_string(plan.runs) +
                     (plan.runs == 1 ? " run" : " runs") + " (rules × settings × seeds)";
  if (settings_.has("time")) {
    const double budget = settings_.real("time") * static_cast<double>(plan.runs);
    line += ", " + format_value(settings_.real("time")) +
            " s each, evaluations and checkpoints included: about " + duration_text(budget) +
            " for the runs";
  } else {
    line += "; the time left shows once training starts";
  }
  plan.announcement = line;
}

const LearningResult& LearningSweep::run(const std::string& id, const std::string& tag,
                                         const nlohmann::json& params, Network& network,
                                         const LearningProblem& problem,
                                         const Dataset& train_set, const Dataset* test_set,
                                         std::function<void(const Network&, TrainingRecord&)> observe) {
  const SwitchingUpdate* switching = nullptr;
  const std::unique_ptr<LearningUpdate> update = run_update(id, switching);
  const std::string pretrained = pretrained_rule(id);

  LearningResult result;
  result.id = id;
  result.tag = tag;
  result.label = learning_run_label(id) + " (" +
                 (is_control_run(id) ? "lr ×" + format_value(*control_factor()) + "; " : "") +
                 tag + ")";
  result.seed = params.value("seed", 0LL);

  TrainerOptions options = trainer_options(pretrained.empty() ? id : pretrained, result.seed);
  if (observe) {
    options.on_evaluate = [&network, observe](const Network&, TrainingRecord& record) {
      observe(network, record);
    };
  }
  SweepRunProgress progress(context_, options);
  options.on_progress = [&](const TrainingRecord& r) { progress.evaluated(result, options, r); };
  result.summary = train_or_resume(RunKey{context_.next_learning_run(), id, tag, result.seed},
                                   network, *update, problem, train_set, test_set, options);
  ++context_.run_plan().finished;
  result.params = trained_params(*update, options.batch_size, switching, result);
  progress.finished(result);
  record_run(result, network, params);
  results_.push_back(std::move(result));
  return results_.back();
}

std::unique_ptr<LearningUpdate> LearningSweep::run_update(const std::string& id,
                                                          const SwitchingUpdate*& switching) const {
  // A pretrained run: its Adam part as the Adam run of this sweep (with --pretrain-<option>),
  // then its rule; the control: then a fresh Adam at control_factor() × the Adam part's step.
  const std::string pretrained = pretrained_rule(id);
  switching = nullptr;
  if (pretrained.empty()) return make_update(id);
  const std::optional<SwitchCondition> condition = switch_condition();
  if (!condition) {
    throw Error(context_.experiment_name() + ": run '" + id +
                "' needs --pretrain auto or N, N below the --iters limit if one is given");
  }
  const RuleSettings adam_part = pretraining_settings();
  std::unique_ptr<LearningUpdate> first = make_update(kPretrainingRule, adam_part);
  RuleSettings control = adam_part;
  if (is_control_run(id)) {
    if (!control_factor()) throw Error(context_.experiment_name() + ": the control is off");
    control["lr"] = *control_factor() * first->learning_rate();
  }
  auto composed = std::make_unique<SwitchingUpdate>(
      std::move(first), batch_size(kPretrainingRule),
      is_control_run(id) ? make_update(kPretrainingRule, control) : make_update(pretrained),
      batch_size(pretrained), *condition);
  switching = composed.get();
  return composed;
}

TrainerOptions LearningSweep::trainer_options(const std::string& rule, long long seed) const {
  TrainerOptions options;
  options.batch_size = batch_size(rule);
  if (settings_.has("iters")) options.max_iterations = settings_.integer("iters");
  if (settings_.has("epochs")) options.max_epochs = settings_.integer("epochs");
  if (settings_.has("time")) options.time_budget_seconds = settings_.real("time");
  // A run limited by time alone is also evaluated by time, so that slow rules get as many
  // points as fast ones; runs with an iteration or epoch limit keep the iteration schedule
  // alone, which a resumed or data-parallel run reproduces exactly.
  if (settings_.has("time") && !settings_.has("iters") && !settings_.has("epochs")) {
    options.eval_seconds = settings_.real("time") / kEvaluationsOverTime;
  }
  if (settings_.has("eval-every")) options.eval_every = settings_.integer("eval-every");
  options.seed = static_cast<std::uint64_t>(seed);
  if (settings_.has("data") && settings_.text("data") == "fresh") {
    if (!fresh_samples_) {
      throw Error(context_.experiment_name() + ": --data fresh: this experiment draws no fresh "
                  "samples");
    }
    options.fresh_samples = fresh_samples_;
  }
  options.communicator = context_.communicator();
  // The yardstick of every rule's cost: an Adam update of the sweep's Adam run, timed beside it.
  options.cost_reference = [this] { return make_update(kPretrainingRule); };
  options.cost_reference_batch = batch_size(kPretrainingRule);
  return options;
}

nlohmann::json LearningSweep::trained_params(const LearningUpdate& update, Index batch,
                                             const SwitchingUpdate* switching,
                                             LearningResult& result) const {
  nlohmann::json run_params = update.params();
  run_params["batch"] = batch;
  if (switching != nullptr) {
    // Where the rule took over (the second part's first iteration), or that it never did: then
    // the run is Adam's alone and reads so.
    const auto& phases = result.summary.phases;
    run_params["switched"] = phases.size() > 1;
    if (is_control_run(result.id)) run_params["control_lr_factor"] = *control_factor();
    if (phases.size() > 1) {
      run_params["pretrain_iterations"] = phases[1].first_iteration;
    } else {
      result.label = learning_run_label(kPretrainingRule) + " (" + result.tag +
                     "; never switched to " + taking_over_label(result.id, run_params) + ")";
    }
  }
  return run_params;
}

void LearningSweep::record_run(const LearningResult& result, const Network& network,
                               const nlohmann::json& params) {
  context_.add_network({{"label", result.label},
                        {"seed", result.seed},
                        {"network", network.describe()},
                        {"parameters", vector_to_json(network.parameters())}});
  for (const TrainingRecord& r : result.summary.history) {
    nlohmann::json row = {{"label", result.label},  {"optimizer", result.id},
                          {"iteration", r.iteration}, {"epoch", r.epoch},
                          {"wall_seconds", r.train_seconds}, {"train_loss", r.train_loss},
                          {"test_loss", r.test_loss}};
    for (const auto& [key, value] : params.items()) row[key] = value;
    for (const auto& [key, value] : r.extras.items()) row[key] = value;
    for (const auto& [key, value] : r.step.items()) row[key] = value;
    context_.add_metrics_row(std::move(row));
  }
  const TrainingSummary& s = result.summary;
  RunEntry entry;
  entry.label = result.label;
  entry.optimizer = result.id;
  entry.params = result.params;
  for (const auto& [key, value] : params.items()) entry.params[key] = value;
  entry.initial.loss = s.history.front().train_loss;
  entry.initial.test_loss = s.history.front().test_loss;
  entry.final.loss = s.history.back().train_loss;
  entry.final.test_loss = s.history.back().test_loss;
  for (const auto& [key, value] : s.history.back().extras.items()) entry.final.more[key] = value;
  entry.iterations = s.iterations;
  entry.epochs = s.history.back().epoch;
  entry.wall_seconds = s.train_seconds;
  entry.run_seconds = s.wall_seconds;  // evaluations and checkpoints included
  entry.termination = to_string(*s.termination);
  entry.message = s.message;
  entry.step_halvings = s.step_halvings;
  entry.seconds_per_part = SecondsPerPart{s.forward_seconds, s.derivative_seconds,
                                          s.inversion_seconds, s.update_seconds};
  // The cost per update in Adam updates timed beside the rule's steps; a twin's per part.
  const double adam_updates = adam_updates_per_update(result);
  if (std::isfinite(adam_updates)) entry.more["adam_updates_per_update"] = adam_updates;
  for (const PhaseCost& phase : phase_costs(result)) {
    nlohmann::json part = {{"rule", phase.rule},
                           {"updates", phase.updates},
                           {"train_seconds", phase.seconds},
                           {"seconds_per_update", phase.seconds_per_update()}};
    if (std::isfinite(phase.adam_updates_per_update)) {
      part["adam_updates_per_update"] = phase.adam_updates_per_update;
    }
    entry.more["phases"].push_back(std::move(part));
  }
  context_.add_run(std::move(entry));
}

std::unique_ptr<LearningUpdate> LearningSweep::make_update(const std::string& rule,
                                                           const RuleSettings& overrides) const {
  const RuleDefaults* own = experiment_setting(defaults_, rule);
  RuleSettings options = own == nullptr ? RuleSettings{} : own->settings;
  for (const auto& [name, value] : rule_settings(settings_, RuleKind::kLearning)) {
    options[name] = value;
  }
  for (const auto& [name, value] : overrides) options[name] = value;
  return make_learning_update(rule, options);
}

Index LearningSweep::batch_size(const std::string& rule) const {
  if (settings_.has("batch")) return settings_.integer("batch");
  const RuleDefaults* own = experiment_setting(defaults_, rule);
  return (own == nullptr ? std::nullopt : own->batch).value_or(TrainerOptions{}.batch_size);
}

}  // namespace physgrad::run
