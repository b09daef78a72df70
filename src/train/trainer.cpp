#include "physgrad/train/trainer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/stop.hpp"
#include "physgrad/text.hpp"
#include "physgrad/timing.hpp"

namespace physgrad {

namespace {

using Clock = std::chrono::steady_clock;

constexpr NameTable<TrainingTermination, 5> kTerminationNames{{
    {TrainingTermination::kMaxIterations, "max_iterations"},
    {TrainingTermination::kMaxEpochs, "max_epochs"},
    {TrainingTermination::kTimeBudget, "time_budget"},
    {TrainingTermination::kNumericalFailure, "numerical_failure"},
    {TrainingTermination::kInterrupted, "interrupted"},
}};

// Samples seen / training samples: iterations · batch size / samples, the pretraining's
// updates at its batch size.
double epochs(const TrainingSummary& s) {
  if (s.samples <= 0) return 0.0;
  const long long pretrained =
      s.pretraining ? std::min(s.iterations, s.pretraining->iterations) : 0;
  const double seen =
      static_cast<double>(pretrained) *
          static_cast<double>(s.pretraining ? s.pretraining->batch_size : 0) +
      static_cast<double>(s.iterations - pretrained) * static_cast<double>(s.batch_size);
  return seen / static_cast<double>(s.samples);
}

void check_trainer_options(const TrainerOptions& options) {
  const auto at_least_one = [](const char* name, const std::optional<long long>& value) {
    if (value && *value < 1) {
      throw Error(std::string(name) + " must be ≥ 1, got " + std::to_string(*value));
    }
  };
  if (options.batch_size < 1) {
    throw Error("batch size must be ≥ 1, got " + std::to_string(options.batch_size));
  }
  if (!options.max_iterations && !options.max_epochs && !options.time_budget_seconds) {
    throw Error("training needs a limit: max_iterations, max_epochs or time_budget_seconds");
  }
  at_least_one("max_iterations", options.max_iterations);
  at_least_one("max_epochs", options.max_epochs);
  at_least_one("eval_every", options.eval_every);
  at_least_one("checkpoint_every", options.checkpoint_every);
  if (options.time_budget_seconds && !(*options.time_budget_seconds > 0)) {
    throw Error("time budget must be > 0 seconds");
  }
  if (options.eval_seconds && !(*options.eval_seconds > 0)) {
    throw Error("eval_seconds must be > 0");
  }
  if (options.checkpoint_seconds && !(*options.checkpoint_seconds >= 0)) {
    throw Error("checkpoint_seconds must be ≥ 0");
  }
  if (options.max_step_halvings < 0) {
    throw Error("max_step_halvings must be ≥ 0, got " + std::to_string(options.max_step_halvings));
  }
  if (const std::optional<Pretraining>& p = options.pretraining) {
    if (p->update == nullptr) throw Error("pretraining: no update rule");
    if (p->batch_size < 1) {
      throw Error("pretraining: batch size must be ≥ 1, got " + std::to_string(p->batch_size));
    }
    if (p->iterations < 1) {
      throw Error("pretraining: iterations must be ≥ 1, got " + std::to_string(p->iterations));
    }
    if (options.max_iterations && p->iterations >= *options.max_iterations) {
      throw Error("pretraining: its " + std::to_string(p->iterations) +
                  " iterations leave none of the max_iterations " +
                  std::to_string(*options.max_iterations) + " to the run's rule");
    }
  }
}

// One training run: the loop state between iterations (what a checkpoint holds) around
// train_step().
class TrainingRun {
 public:
  TrainingRun(Network& network, LearningUpdate& update, const LearningProblem& problem,
              const Dataset& train_set, const Dataset* test_set, const TrainerOptions& options)
      : network_(network),
        update_(update),
        problem_(problem),
        train_set_(train_set),
        test_set_(test_set),
        options_(options),
        n_(train_set.size()),
        run_batch_size_(std::min(options.batch_size, train_set.size())),
        pretraining_batch_size_(
            options.pretraining ? std::min(options.pretraining->batch_size, train_set.size()) : 0) {
    if (options.pretraining && options.pretraining->update == &update) {
      throw Error("pretraining: its update rule is the run's own; give it another object");
    }
    step_state_.shard = Shard(options.communicator);
    step_state_.max_step_halvings = options.max_step_halvings;
  }

  TrainingSummary run();

 private:
  // With a pretraining, its rule makes the updates after fewer than its iterations; the run's
  // rule makes the others.
  bool pretrains_after(long long iterations) const {
    return options_.pretraining && iterations < options_.pretraining->iterations;
  }
  LearningUpdate& rule_after(long long iterations) const {
    return pretrains_after(iterations) ? *options_.pretraining->update : update_;
  }
  // Where the data order stands after `iterations` updates: (epoch, start of the next batch).
  // Every epoch of one rule takes the same number of batches; the run's rule begins a new epoch
  // when it takes over from a pretraining.
  std::pair<long long, Index> position(long long iterations) const;
  // The pretraining's last update was made: the run's rule takes over.
  void end_pretraining();
  void restore(const TrainerState& state);
  // What happens between two iterations besides the iteration schedule: a stop request, the
  // time budget and an evaluation due by time, agreed by all ranks of a data-parallel run (any
  // rank's counts), so that every rank stops and evaluates at the same iteration.
  struct Requests {
    bool stop = false;
    bool time_out = false;
    bool evaluate = false;
  };
  Requests requests() const;
  bool evaluate();
  bool step(const std::vector<Index>& batch);
  void stop_for_numbers(const std::string& message);
  bool checkpoint_due() const;
  void checkpoint();
  // Sets what ran in the summary: the rule, its settings, the problem's size and the limits.
  void describe_run();
  // Saves a checkpoint and ends with kInterrupted and `message`.
  TrainingSummary interrupted(std::string message);
  bool ended() const { return summary_.termination.has_value(); }

  Network& network_;
  LearningUpdate& update_;
  const LearningProblem& problem_;
  const Dataset& train_set_;
  const Dataset* test_set_;
  const TrainerOptions& options_;
  const Index n_;
  const Index run_batch_size_;
  const Index pretraining_batch_size_;  // 0 without a pretraining

  // The rule making the updates now and its batch size: the pretraining's, then the run's.
  LearningUpdate* rule_ = nullptr;
  Index batch_size_ = 0;

  TrainingSummary summary_;
  StepState step_state_;
  long long epoch_ = 0;
  Index batch_start_ = 0;
  Vector last_evaluated_;
  bool evaluated_ = false;  // θ is the one of the last history record
  Clock::time_point last_checkpoint_time_ = Clock::now();
  long long last_checkpoint_iteration_ = 0;
};

TrainingSummary TrainingRun::run() {
  // Ranks stop together at an iteration boundary (requests()); none may leave a step alone.
  std::optional<DeferStopPolls> ranks_stop_together;
  if (step_state_.shard.active()) ranks_stop_together.emplace();
  update_.reset();
  if (options_.pretraining) options_.pretraining->update->reset();
  rule_ = &rule_after(0);
  batch_size_ = pretrains_after(0) ? pretraining_batch_size_ : run_batch_size_;
  if (options_.resume != nullptr) restore(*options_.resume);
  describe_run();
  if (options_.resume == nullptr) evaluate();
  last_checkpoint_iteration_ = summary_.iterations;
  while (!ended()) {
    if (batch_start_ == 0 && options_.max_epochs && epoch_ >= *options_.max_epochs) {
      summary_.termination = TrainingTermination::kMaxEpochs;
      break;
    }
    std::vector<Index> order(static_cast<std::size_t>(n_));
    if (options_.shuffle) {
      order = shuffled_indices(n_, options_.seed + static_cast<std::uint64_t>(epoch_));
    } else {
      std::iota(order.begin(), order.end(), Index{0});
    }
    while (batch_start_ < n_ && !ended()) {
      const Requests pending = requests();
      if (pending.stop) {
        return interrupted("stopped on request after iteration " +
                           std::to_string(summary_.iterations));
      }
      if (pending.evaluate && !evaluate()) break;
      if (checkpoint_due()) checkpoint();
      if (options_.max_iterations && summary_.iterations >= *options_.max_iterations) {
        summary_.termination = TrainingTermination::kMaxIterations;
      } else if (pending.time_out) {
        summary_.termination = TrainingTermination::kTimeBudget;
      }
      if (ended()) break;
      const Index count = std::min(batch_size_, n_ - batch_start_);
      const auto first = order.begin() + batch_start_;
      try {
        if (!step(std::vector<Index>(first, first + count))) break;
      } catch (const StopRequested&) {  // train_step() left θ as it was before the step
        return interrupted("stopped on request during iteration " +
                           std::to_string(summary_.iterations + 1) + " (not applied)");
      }
      batch_start_ += batch_size_;
      if (options_.eval_every && summary_.iterations % *options_.eval_every == 0) evaluate();
      if (rule_ != &rule_after(summary_.iterations)) {
        if (!evaluated_ && !evaluate()) break;
        end_pretraining();
        break;
      }
    }
    if (ended()) break;
    if (batch_start_ == 0) continue;  // the run's rule took over: a new epoch has begun
    ++epoch_;
    batch_start_ = 0;
    if (!options_.eval_every) evaluate();
  }
  if (!evaluated_) evaluate();
  if (rule_ != &update_ && summary_.termination != TrainingTermination::kNumericalFailure) {
    summary_.message += std::string(summary_.message.empty() ? "" : "; ") +
                        "ended in the pretraining (" + rule_->id() + "), before " + update_.id() +
                        " took over";
  }
  return summary_;
}

std::pair<long long, Index> TrainingRun::position(long long iterations) const {
  const auto batches = [this](Index batch_size) {
    return static_cast<long long>((n_ + batch_size - 1) / batch_size);
  };
  long long first_epoch = 0;
  if (options_.pretraining) {
    const long long per_epoch = batches(pretraining_batch_size_);
    if (pretrains_after(iterations)) {
      return {iterations / per_epoch, (iterations % per_epoch) * pretraining_batch_size_};
    }
    const long long pretrained = options_.pretraining->iterations;
    first_epoch = (pretrained + per_epoch - 1) / per_epoch;
    iterations -= pretrained;
  }
  const long long per_epoch = batches(run_batch_size_);
  return {first_epoch + iterations / per_epoch, (iterations % per_epoch) * run_batch_size_};
}

void TrainingRun::end_pretraining() {
  rule_ = &update_;
  batch_size_ = run_batch_size_;
  std::tie(epoch_, batch_start_) = position(summary_.iterations);
}

void TrainingRun::restore(const TrainerState& state) {
  const Index count = network_.num_parameters();
  const auto fits = [count](const Vector& v, bool may_be_empty) {
    return v.size() == count || (may_be_empty && v.size() == 0);
  };
  const long long iterations = state.summary.iterations;
  const Index batch_size = pretrains_after(iterations) ? pretraining_batch_size_ : run_batch_size_;
  std::string problem;
  if (!fits(state.parameters, false) || !fits(state.last_evaluated, false) ||
      !fits(state.last_step, true) || state.before_last_step.size() != state.last_step.size()) {
    problem = "its vectors do not have the network's " + std::to_string(count) + " weights";
  } else if (state.epoch < 0 || state.batch_start < 0 || state.batch_start >= n_ ||
             state.batch_start % batch_size != 0) {
    problem = "epoch " + std::to_string(state.epoch) + ", batch start " +
              std::to_string(state.batch_start) + " do not fit " + std::to_string(n_) +
              " samples in batches of " + std::to_string(batch_size);
  } else if (iterations < 0 ||
             position(iterations) != std::make_pair(state.epoch, state.batch_start)) {
    // The position follows from the count (position()).
    problem = "epoch " + std::to_string(state.epoch) + " and batch start " +
              std::to_string(state.batch_start) + " do not follow from its " +
              std::to_string(iterations) + " iterations in batches of " +
              std::to_string(batch_size) + " of " + std::to_string(n_) + " samples" +
              (options_.pretraining ? " after a pretraining of " +
                                          std::to_string(options_.pretraining->iterations)
                                    : "");
  } else if (state.summary.history.empty() || state.summary.termination) {
    problem = "it has no history or belongs to a finished run";
  }
  if (!problem.empty()) throw Error("cannot resume training from this state: " + problem);
  rule_ = &rule_after(iterations);
  batch_size_ = batch_size;
  network_.set_parameters(state.parameters);
  rule_->restore(state.update_state, count);
  summary_ = state.summary;
  epoch_ = state.epoch;
  batch_start_ = state.batch_start;
  step_state_.last_step = state.last_step;
  step_state_.before_last_step = state.before_last_step;
  step_state_.last_step_halvable =
      iterations > 0 && rule_after(iterations - 1).steps_can_be_halved();
  last_evaluated_ = state.last_evaluated;
  evaluated_ = summary_.history.back().iteration == summary_.iterations &&
               network_.parameters() == last_evaluated_;
}

// Records the losses of the current θ. A non-finite loss stops training with θ restored to the
// last evaluated parameters (the untrained network's is an Error: nothing to go back to).
bool TrainingRun::evaluate() {
  TrainingRecord record;
  record.iteration = summary_.iterations;
  record.epoch = epochs(summary_);
  record.train_seconds = summary_.train_seconds;
  record.train_loss = mean_loss(network_, problem_, train_set_, step_state_.shard);
  record.test_loss =
      test_set_ ? mean_loss(network_, problem_, *test_set_, step_state_.shard) : NAN;
  const char* bad = !std::isfinite(record.train_loss)                          ? "train"
                    : test_set_ != nullptr && !std::isfinite(record.test_loss) ? "test"
                                                                               : nullptr;
  if (bad != nullptr) {
    if (summary_.history.empty()) {
      throw Error(std::string("the untrained network's ") + bad +
                  " loss is not finite; check the data and the simulator");
    }
    network_.set_parameters(last_evaluated_);
    evaluated_ = true;
    stop_for_numbers(std::string("non-finite ") + bad + " loss at the evaluation after iteration " +
                     std::to_string(summary_.iterations) +
                     "; parameters restored to those evaluated at iteration " +
                     std::to_string(summary_.history.back().iteration));
    return false;
  }
  if (options_.on_evaluate) options_.on_evaluate(network_, record);
  if (summary_.iterations > 0) record.step = rule_->step_info();
  summary_.history.push_back(record);
  last_evaluated_ = network_.parameters();
  evaluated_ = true;
  if (options_.on_progress) options_.on_progress(record);
  return true;
}

// One update on the samples `batch`; false when training must stop. Every rank of a
// data-parallel run sees the same combined numbers and takes the same branches.
bool TrainingRun::step(const std::vector<Index>& batch) {
  const StepReport report = train_step(network_, *rule_, problem_, train_set_.select(batch),
                                       step_state_);
  summary_.forward_seconds += report.forward_seconds;
  summary_.derivative_seconds += report.derivative_seconds;
  summary_.inversion_seconds += report.inversion_seconds;
  summary_.step_halvings += report.halvings;
  summary_.counts += report.counts;
  evaluated_ = evaluated_ && !report.applied() && !report.undone && report.halvings == 0;
  if (!report.applied()) {
    stop_for_numbers(rule_->id() + ": " + describe_failure(report, summary_.iterations));
    return false;
  }
  summary_.update_seconds += report.update_seconds;
  summary_.train_seconds += report.total_seconds;
  ++summary_.iterations;
  return true;
}

void TrainingRun::stop_for_numbers(const std::string& message) {
  summary_.termination = TrainingTermination::kNumericalFailure;
  summary_.message += (summary_.message.empty() ? "" : "; then ") + message;
}

TrainingSummary TrainingRun::interrupted(std::string message) {
  checkpoint();
  summary_.termination = TrainingTermination::kInterrupted;
  summary_.message = std::move(message);
  return summary_;
}

TrainingRun::Requests TrainingRun::requests() const {
  const bool evaluation_due =
      options_.eval_seconds && !evaluated_ &&
      summary_.train_seconds - summary_.history.back().train_seconds >= *options_.eval_seconds;
  double flags[3] = {
      (options_.stop != nullptr && options_.stop->load()) || stop_requested() ? 1.0 : 0.0,
      options_.time_budget_seconds && summary_.train_seconds >= *options_.time_budget_seconds
          ? 1.0
          : 0.0,
      evaluation_due ? 1.0 : 0.0};
  step_state_.shard.sum(flags, 3);
  return {flags[0] > 0, flags[1] > 0, flags[2] > 0};
}

bool TrainingRun::checkpoint_due() const {
  if (!options_.on_checkpoint || summary_.iterations == last_checkpoint_iteration_) return false;
  return (options_.checkpoint_every && summary_.iterations % *options_.checkpoint_every == 0) ||
         (options_.checkpoint_seconds &&
          seconds_since(last_checkpoint_time_) >= *options_.checkpoint_seconds);
}

void TrainingRun::describe_run() {
  summary_.update = update_.id();
  summary_.params = update_.params();
  summary_.parameters = network_.num_parameters();
  summary_.samples = n_;
  summary_.batch_size = run_batch_size_;
  summary_.pretraining.reset();
  if (const std::optional<Pretraining>& p = options_.pretraining) {
    summary_.pretraining = TrainingSummary::Pretraining{p->update->id(), p->update->params(),
                                                        pretraining_batch_size_, p->iterations};
  }
  summary_.limits.clear();
  const auto limit = [this](const char* name, const auto& value) {
    if (value) summary_.limits.emplace_back(name, static_cast<double>(*value));
  };
  limit("max_iterations", options_.max_iterations);
  limit("max_epochs", options_.max_epochs);
  limit("time_budget_seconds", options_.time_budget_seconds);
}

void TrainingRun::checkpoint() {
  if (options_.on_checkpoint) {
    TrainerState state;
    state.epoch = epoch_;
    state.batch_start = batch_start_;
    state.parameters = network_.parameters();
    state.last_step = step_state_.last_step;
    state.before_last_step = step_state_.before_last_step;
    state.last_evaluated = last_evaluated_;
    state.update_state = rule_->state();
    state.summary = summary_;
    options_.on_checkpoint(state);
  }
  last_checkpoint_time_ = Clock::now();
  last_checkpoint_iteration_ = summary_.iterations;
}

}  // namespace

std::string to_string(TrainingTermination termination) {
  return name_of(kTerminationNames, termination, "TrainingTermination");
}

TrainingTermination parse_training_termination(const std::string& text) {
  return value_named(kTerminationNames, text, "training termination");
}

std::string brief_report(const TrainingSummary& s) {
  const double initial = s.history.empty() ? NAN : s.history.front().train_loss;
  const double final_loss = s.history.empty() ? NAN : s.history.back().train_loss;
  std::string pretrained;
  if (s.pretraining) {
    pretrained = " after " + std::to_string(std::min(s.iterations, s.pretraining->iterations)) +
                 " iterations of " + s.pretraining->update;
  }
  return s.update + pretrained + ": " + std::to_string(s.iterations) + " iterations (" +
         report_number(epochs(s)) + " epochs), " + std::to_string(s.counts.passes) +
         " simulator passes, train loss " + report_number(initial) + " → " +
         report_number(final_loss) + ", " +
         (s.termination ? to_string(*s.termination) : std::string("in progress"));
}

std::string full_report(const TrainingSummary& s) {
  std::string out = "physgrad training report\n\nProblem\n";
  out += report_row("parameters", std::to_string(s.parameters));
  out += report_row("training samples", std::to_string(s.samples));
  out += report_row("batch size", std::to_string(s.batch_size));
  out += "\nRule\n";
  out += report_row("update", s.update);
  const auto add_params = [&out](const nlohmann::json& params) {
    for (const auto& [name, value] : params.items()) {
      out += report_row(name, value.is_string() ? value.get<std::string>() : value.dump());
    }
  };
  add_params(s.params);
  if (s.pretraining) {
    out += "\nPretraining (its rule makes the first updates)\n";
    out += report_row("update", s.pretraining->update);
    out += report_row("iterations", std::to_string(s.pretraining->iterations));
    out += report_row("batch size", std::to_string(s.pretraining->batch_size));
    add_params(s.pretraining->params);
  }
  out += "\nLimits\n";
  for (const auto& [name, value] : s.limits) out += report_row(name, report_number(value));
  if (!s.history.empty()) {
    const TrainingRecord& first = s.history.front();
    const TrainingRecord& last = s.history.back();
    out += "\nLoss (train, test)\n";
    const auto losses = [](const TrainingRecord& r) {
      return report_number(r.train_loss) + ", " + report_number(r.test_loss);
    };
    out += report_row("initial", losses(first));
    out += report_row("final (iteration " + std::to_string(last.iteration) + ")", losses(last));
    out += report_row("change (train)", report_number(first.train_loss - last.train_loss));
  }
  out += "\nWork\n";
  out += report_row("iterations", std::to_string(s.iterations));
  out += report_row("epochs", report_number(epochs(s)));
  out += report_row("evaluations", std::to_string(s.history.size()));
  out += report_row("step halvings", std::to_string(s.step_halvings));
  out += report_row("simulator passes", std::to_string(s.counts.passes));
  for (const auto& [name, field] : SimulatorCounts::fields()) {
    if (field == &SimulatorCounts::passes) continue;
    out += report_row("  " + std::string(name), std::to_string(s.counts.*field));
  }
  out += "\nTime (seconds)\n";
  out += report_row("network + physics", report_number(s.forward_seconds));
  out += report_row("derivatives", report_number(s.derivative_seconds));
  out += report_row("inversion", report_number(s.inversion_seconds));
  out += report_row("rest of the update", report_number(s.update_seconds));
  out += report_row("training", report_number(s.train_seconds));
  out += "\nTermination: " +
         (s.termination ? to_string(*s.termination) : std::string("in progress")) +
         (s.message.empty() ? "" : " (" + s.message + ")") + "\n";
  return out;
}

TrainingSummary train(Network& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& train_set, const Dataset* test_set,
                      const TrainerOptions& options) {
  check_problem(network, problem, train_set, "training set");
  if (test_set != nullptr) check_problem(network, problem, *test_set, "test set");
  check_trainer_options(options);
  return TrainingRun(network, update, problem, train_set, test_set, options).run();
}

}  // namespace physgrad
