// Shared pieces of the learning experiments: train one configuration per (rule, setting,
// seed) with the common options, record metrics and summaries, and build the comparison
// tables (per-seed final losses with median and worst, time split per step) and loss figures.
#pragma once

#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "physgrad/run/life/experiment.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/learn/switching.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/report/line_plot.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad::run {

struct RunKey;
struct LearningCase;  // learning_case.hpp

struct LearningResult {
  std::string id;     // update rule id, or a pretrained run's ("adam-hig", catalogue.hpp)
  std::string tag;    // the setting, e.g. "λ=0.01"
  std::string label;  // "HIG (λ=0.01)", "Adam→HIG (λ=0.01)"
  long long seed = 0;
  // The rule's params() and the batch size; for a pretrained run also its switch condition
  // (SwitchingUpdate::params()), "switched" and, when it did, pretrain_iterations (the updates
  // Adam made before its rule took over). A run that never switched is labelled as Adam's.
  nlohmann::json params;
  TrainingSummary summary;
};

// The control arm beside the twins (--control, --control-lr-factor): Adam until the twins' switch,
// then a fresh Adam at a smaller step, "adam-adam" (pretrained_run_id(kPretrainingRule)).
bool is_control_run(const std::string& id);
// The rule run `id` with `params` (LearningResult::params) stands for in the verdict, the tables
// and the notes: learning_run_label(id), for the control with its step, "Adam→Adam (lr ×0.1)"
// (from params' control_lr_factor).
std::string run_rule_label(const std::string& id, const nlohmann::json& params);
// The rule that takes over in a twin: "HIG" in Adam→HIG, "Adam at lr ×0.1" in the control.
std::string taking_over_label(const std::string& id, const nlohmann::json& params);

// One part of a run made of parts (a twin: Adam, then its rule): the part's rule id, its updates
// and their training seconds (evaluations excluded).
struct PhaseCost {
  std::string rule;
  long long updates = 0;
  double seconds = 0;
  // Its cost per update in Adam updates timed beside its steps (1 for Adam; NaN unprobed).
  double adam_updates_per_update = NAN;
  double seconds_per_update() const;  // NaN without updates
};
// The parts of a twin (its params have "switched"): Adam's updates up to the switch, measured at
// the evaluation made there, and its rule's after it (Adam's alone when it never switched); empty
// for a plain rule.
std::vector<PhaseCost> phase_costs(const LearningResult& run);
// The training seconds per update of a run's rule: the whole run's, or for a twin (params with
// "pretrain_iterations") its evaluations' from the switch on, so that Adam's cheaper updates
// before it are not mixed in; NaN when the rule made no update between two evaluations.
double rule_seconds_per_update(const LearningResult& run);

// What one update of the run's rule (a twin's: of its rule after the switch) costs in Adam
// updates, from the cost probes timed beside its steps in its own process
// (TrainerOptions::cost_reference): 1 for Adam and the control, NaN when it made none.
double adam_updates_per_update(const LearningResult& run);

// An experiment's choices for one rule where they differ from the catalogue's defaults, and its
// mini-batch size (unset: TrainerOptions' default); --lr, --rcond and --batch override them for
// every rule (the Adam part of a pretrained run included, unless --pretrain-lr, … give it its
// own). A rule the experiment gives none takes
// those of its settings_source() (catalogue.hpp): kfac-hig and lanczos-hig those of hig.
struct RuleDefaults {
  RuleSettings settings;
  std::optional<Index> batch;
};

// On a log y axis, a series that ends above where it started (a diverging run) does not set the
// axis range, and its end label says where it ends relative to its start.
void mark_if_diverging(Series& series);

// Controls u₀ … u_{N−1}, each held for dt, as steps over [0, N·dt].
Series held_controls(const std::string& label, const Vector& u, double dt,
                     const std::string& color);

// Reads the common and learning options; trains, records and tabulates the runs.
class LearningSweep {
 public:
  LearningSweep(const Settings& settings, RunContext& context,
                std::map<std::string, RuleDefaults> defaults);
  // The sweep of a case: its rule defaults, and its samples for --data fresh (draw_from).
  LearningSweep(const Settings& settings, RunContext& context, const LearningCase& learning_case);

  // The rules the experiment runs when --optimizers is not given (it chose them): their runs
  // (run_ids) are the run count the progress lines plan with. The first call counts.
  void plan_runs(const std::vector<std::string>& rules);

  // The runs of `rules`, in order: each rule, and after each rule that needs the stacked
  // Jacobian (gn, hig, kfac, lanczos-hig, …), when --pretrain is auto or N (N > 0 and below the
  // --iters limit), its run pretrained with Adam ("adam-hig"), and after them all, when any ran
  // and --control is not off, the control ("adam-adam"). With --alone off a rule that has a twin
  // runs only as its twin. An experiment trains each of these ids.
  std::vector<std::string> run_ids(const std::vector<std::string>& rules) const;

  // Trains `network` (any Network: an Mlp, a ConvNetwork, …) with rule `id` and records it (its
  // describe() and trained θ go to networks.json); `params` (e.g. {"lambda", "seed"}) are
  // added to the summary entry and to every metrics row. A pretrained run ("adam-hig") is a
  // SwitchingUpdate: Adam, with the settings and batch size of this sweep's Adam run (or those
  // --pretrain-<option> give), until --pretrain's condition holds (N updates, or a plateau of its
  // evaluated training loss: --plateau-window, --plateau-fraction), then the rule continues from
  // that network to the end of the run's limits (which count the whole run); its history is one
  // curve. The control ("adam-adam") continues with a fresh Adam at --control-lr-factor × the
  // Adam part's step instead. With --data
  // fresh (and draw_from() called), every batch is drawn afresh.
  const LearningResult& run(const std::string& id, const std::string& tag,
                            const nlohmann::json& params, Network& network,
                            const LearningProblem& problem, const Dataset& train_set,
                            const Dataset* test_set,
                            std::function<void(const Network&, TrainingRecord&)> observe = {});

  // Where --data fresh is set, the runs draw every mini-batch from `source` (TrainerOptions::
  // fresh_samples) instead of the training set.
  void draw_from(SampleSource source) { fresh_samples_ = std::move(source); }

  // The first-seed run of every rule for `tag`, in the order they ran.
  std::vector<const LearningResult*> first_seed_runs(const std::string& tag) const;
  // Every run (all seeds) of each rule for `tag`, one group per rule in the order they ran.
  std::vector<std::vector<const LearningResult*>> rule_groups(const std::string& tag) const;

  // What the x axis of a training-progress figure counts.
  enum class Progress { kTime, kIteration, kEpoch };
  // A per-evaluation value of each rule against `progress`: the median over the group's runs
  // (seeds) with their min–max band, a dot at every evaluation, and runs that stopped on
  // non-finite numbers marked at their end.
  static void add_metric_figure(RunContext& context,
                                const std::vector<std::vector<const LearningResult*>>& groups,
                                const std::string& file, const std::string& title,
                                const std::string& y_label,
                                const std::function<double(const TrainingRecord&)>& value,
                                Progress progress = Progress::kTime, bool log_y = true);
  // That figure, not added; with `y_range`, its y axis is fitted to that range (figures side by
  // side sharing one axis).
  static RunContext::Figure metric_figure(
      const std::vector<std::vector<const LearningResult*>>& groups, const std::string& file,
      const std::string& title, const std::string& y_label,
      const std::function<double(const TrainingRecord&)>& value, Progress progress, bool log_y,
      std::optional<std::pair<double, double>> y_range = std::nullopt);
  // Test loss vs iteration (or epoch) and vs training time of every rule's runs for `tag`.
  void add_loss_figures(RunContext& context, const std::string& tag, const std::string& file_tag,
                        bool by_epoch = false,
                        const std::string& loss_label = "mean test loss") const;
  // `value` of every rule's runs for `tag` against the updates made (left) and the training time
  // (right), side by side: the figure of a message that judges per update and per second.
  RunContext::Figure progress_figure(const std::string& tag, const std::string& file,
                                     const std::function<double(const TrainingRecord&)>& value,
                                     const std::string& what, const std::string& y_label) const;
  // Makes that figure of the test loss the message (progress_<file_tag>.svg), with the verdict
  // (learning_verdict.hpp): which rule's median final `what` is lowest within the same budget,
  // and per rule against Adam the update advantage and the step-cost ratio.
  void set_time_message(const std::string& tag, const std::string& file_tag,
                        const std::string& what = "final test loss") const;
  // Makes figure `file` the message for a metric other than the loss, the record's extra
  // `metric`: `prefix`, then the verdict on `metric` (`what_metric`), then on the test loss
  // (`what_loss`) after `loss_lead`.
  void set_metric_message(const std::string& tag, const std::string& file,
                          const std::string& metric, const std::string& what_metric,
                          const std::string& loss_lead, const std::string& what_loss,
                          const std::string& prefix = "") const;
  // The value of a record's extra `key` (TrainingRecord::extras, filled by on_evaluate).
  static std::function<double(const TrainingRecord&)> extra(const std::string& key);
  // The labels of the runs of `tag`, in the order they ran (each once).
  std::vector<std::string> labels(const std::string& tag) const;
  // Per setting: final test loss per seed with median and worst; the saturated-neuron
  // fraction when recorded; the time split per step of every rule; and a note on where each
  // pretrained run switched (add_switch_note).
  void add_tables() const;

 private:
  // The steps of run(). The update rule `id` trains with: a pretrained run ("adam-hig") is a
  // SwitchingUpdate, also returned in `switching`.
  std::unique_ptr<LearningUpdate> run_update(const std::string& id,
                                             const SwitchingUpdate*& switching) const;
  // The trainer's limits, evaluations, batch of `rule`, seed and samples from the settings.
  TrainerOptions trainer_options(const std::string& rule, long long seed) const;
  // The run's params after training: the rule's, its batch, and for a pretrained run where it
  // switched (a run that never did is relabelled as Adam's).
  nlohmann::json trained_params(const LearningUpdate& update, Index batch,
                                const SwitchingUpdate* switching, LearningResult& result) const;
  // Its trained network, metrics rows (with `params`) and summary entry into the context.
  void record_run(const LearningResult& result, const Network& network,
                  const nlohmann::json& params);
  // Trains, or takes the run from the context's checkpoint when it finished there, or
  // continues it from its saved state; saves checkpoints as the settings ask. Throws
  // Interrupted when a stop request ended the run.
  TrainingSummary train_or_resume(const RunKey& key, Network& network, LearningUpdate& update,
                                  const LearningProblem& problem, const Dataset& train_set,
                                  const Dataset* test_set, TrainerOptions options);
  // A note saying, for every pretrained run, after how many Adam updates its rule took over.
  void add_switch_note() const;
  // Learning rule `rule` as this sweep runs it: the experiment's choices with the settings given
  // for every rule (--lr, --rcond, …), then `overrides`, and its batch size.
  std::unique_ptr<LearningUpdate> make_update(const std::string& rule,
                                              const RuleSettings& overrides = {}) const;
  // The Adam part of the twins and of the control: the sweep's Adam run with the options given
  // as --pretrain-<option> (--pretrain-lr, --pretrain-schedule, …) in its place.
  RuleSettings pretraining_settings() const;
  // The factor of the control's step over the Adam part's (--control-lr-factor, 0.1 unset);
  // nullopt when it is off (--control off or a factor of 0).
  std::optional<double> control_factor() const;
  // Whether a rule that gets a twin also runs alone from the start (--alone, on unless off).
  bool rules_alone() const;
  Index batch_size(const std::string& rule) const;
  // When pretrained runs are made (--pretrain auto, or N > 0 and below the --iters limit), the
  // condition of their switch from Adam to the rule.
  std::optional<SwitchCondition> switch_condition() const;

  const Settings& settings_;
  RunContext& context_;
  std::map<std::string, RuleDefaults> defaults_;
  std::deque<LearningResult> results_;  // stable addresses
  SampleSource fresh_samples_;
};

}  // namespace physgrad::run
