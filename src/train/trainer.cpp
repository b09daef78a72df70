#include "physgrad/train/trainer.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/stop.hpp"
#include "physgrad/text.hpp"
#include "training_run.hpp"

namespace physgrad {

double TrainingSummary::Phase::reference_updates() const {
  if (probes == 0 || timed_steps == 0 || reference_cpu_seconds <= 0) return NAN;
  return (step_cpu_seconds / static_cast<double>(timed_steps)) /
         (reference_cpu_seconds / static_cast<double>(probes));
}

namespace training {

namespace {

// The most of the training time the cost probes may take (TrainerOptions::cost_reference).
constexpr double kProbeShare = 0.02;

}  // namespace

TrainingSummary TrainingRun::run() {
  // Ranks stop together at an iteration boundary (requests()); none may leave a step alone.
  std::optional<DeferStopPolls> ranks_stop_together;
  if (step_state_.shard.active()) ranks_stop_together.emplace();
  started_ = std::chrono::steady_clock::now();
  update_.reset();
  phase_ = update_.phase();
  batch_size_ = batch_size_now();
  summary_.phases = {{0, batch_size_}};
  if (options_.resume != nullptr) restore(*options_.resume);
  wall_before_ = summary_.wall_seconds;
  describe_run();
  if (options_.resume == nullptr && evaluate() && phase_changed()) begin_phase();
  last_checkpoint_iteration_ = summary_.iterations;
  while (!ended()) {
    if (batch_start_ == 0 && options_.max_epochs && epoch_ >= *options_.max_epochs) {
      end_by_limit(TrainingTermination::kMaxEpochs);
      break;
    }
    std::vector<Index> order(static_cast<std::size_t>(n_));
    if (options_.shuffle) {
      order = shuffled_indices(n_, options_.seed + static_cast<std::uint64_t>(epoch_));
    } else {
      std::iota(order.begin(), order.end(), Index{0});
    }
    bool new_phase = false;
    while (batch_start_ < n_ && !ended() && !new_phase) {
      const Requests pending = requests();
      if (pending.stop) {
        return interrupted("stopped on request after iteration " +
                           std::to_string(summary_.iterations));
      }
      if (pending.evaluate) {
        if (!evaluate()) break;
        if ((new_phase = phase_changed())) break;
      }
      if (checkpoint_due()) checkpoint();
      if (options_.max_iterations && summary_.iterations >= *options_.max_iterations) {
        end_by_limit(TrainingTermination::kMaxIterations);
      } else if (pending.time_out) {
        end_by_limit(TrainingTermination::kTimeBudget);
      } else if (pending.overrun) {
        end_by_limit(TrainingTermination::kTimeBudget, overrun_message(pending.spent));
      }
      if (ended()) break;
      try {
        if (!timed_step(order)) break;
      } catch (const StopRequested&) {  // train_step() left θ as it was before the step
        return interrupted("stopped on request during iteration " +
                           std::to_string(summary_.iterations + 1) + " (not applied)");
      }
      batch_start_ += batch_size_;
      if (options_.eval_every && summary_.iterations % *options_.eval_every == 0 && !evaluate()) {
        break;
      }
      new_phase = phase_changed();
    }
    if (ended()) break;
    if (!new_phase) {
      ++epoch_;
      batch_start_ = 0;
      if (!options_.eval_every && !evaluate()) break;
      new_phase = phase_changed();
    }
    if (new_phase) {
      if (!evaluated_ && !evaluate()) break;
      begin_phase();
    }
  }
  if (!evaluated_) evaluate();
  summary_.wall_seconds = wall_now();
  return summary_;
}

std::string TrainingRun::overrun_message(double spent) const {
  return "time limit: next step would overrun (" + report_number(spent) + " of " +
         report_number(*options_.time_budget_seconds) + " s spent; the last step, evaluation " +
         "and checkpoint took " + report_number(step_cost_) + ", " +
         report_number(evaluation_cost_) + " and " + report_number(checkpoint_cost_) + " s)";
}

void TrainingRun::begin_phase() {
  phase_ = update_.phase();
  batch_size_ = batch_size_now();
  summary_.phases.push_back({summary_.iterations, batch_size_});
  std::tie(epoch_, batch_start_) = position(summary_.iterations);
}

// Records the losses of the current θ and tells the rule. A non-finite loss stops training with
// θ restored to the last evaluated parameters (the untrained network's is an Error: nothing to
// go back to).
bool TrainingRun::evaluate() {
  const auto start = std::chrono::steady_clock::now();
  const bool finite = evaluate_now();
  evaluation_cost_ = seconds_since(start);
  summary_.wall_seconds = wall_now();
  return finite;
}

bool TrainingRun::evaluate_now() {
  TrainingRecord record;
  record.iteration = summary_.iterations;
  record.epoch = epochs_done(summary_);
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
  if (summary_.iterations > 0) record.step = update_.step_info();
  summary_.history.push_back(record);
  last_evaluated_ = network_.parameters();
  evaluated_ = true;
  update_.observe({record.iteration, record.train_loss, record.test_loss});
  if (options_.on_progress) options_.on_progress(record);
  return true;
}

// The next `count` samples of the epoch's order, or as many drawn afresh.
Dataset TrainingRun::batch(const std::vector<Index>& order, Index count) const {
  if (!options_.fresh_samples) {
    const auto first = order.begin() + batch_start_;
    return train_set_.select(std::vector<Index>(first, first + count));
  }
  Dataset drawn = options_.fresh_samples(fresh_stream(options_.seed, summary_.iterations), count);
  if (drawn.size() != count || drawn.inputs.rows() != train_set_.inputs.rows() ||
      drawn.targets.rows() != train_set_.targets.rows() ||
      drawn.context.rows() != train_set_.context.rows()) {
    throw Error("fresh samples: asked for " + std::to_string(count) + " samples of " +
                std::to_string(train_set_.inputs.rows()) + " inputs, got " +
                std::to_string(drawn.size()) + " of " + std::to_string(drawn.inputs.rows()));
  }
  drawn.validate("fresh samples");
  return drawn;
}

bool TrainingRun::timed_step(const std::vector<Index>& order) {
  const auto step_start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_seconds();
  const Dataset drawn = batch(order, std::min(batch_size_, n_ - batch_start_));
  const double draw_cpu = process_cpu_seconds() - cpu_start;
  const std::string part = update_.part_id();  // before a switch inside the step
  const bool stepped = step(drawn);
  if (stepped) probe_cost(drawn, part, process_cpu_seconds() - cpu_start, draw_cpu);
  step_cost_ = seconds_since(step_start);
  return stepped;
}

// One update on `batch`; false when training must stop. Every rank of a data-parallel run sees
// the same combined numbers and takes the same branches.
bool TrainingRun::step(const Dataset& batch) {
  const StepReport report = train_step(network_, update_, problem_, batch, step_state_);
  summary_.forward_seconds += report.forward_seconds;
  summary_.derivative_seconds += report.derivative_seconds;
  summary_.inversion_seconds += report.inversion_seconds;
  summary_.step_halvings += report.halvings;
  summary_.counts += report.counts;
  evaluated_ = evaluated_ && !report.applied() && !report.undone && report.halvings == 0;
  if (!report.applied()) {
    stop_for_numbers(update_.id() + ": " + describe_failure(report, summary_.iterations));
    return false;
  }
  summary_.update_seconds += report.update_seconds;
  summary_.train_seconds += report.total_seconds;
  ++summary_.iterations;
  return true;
}

void TrainingRun::probe_cost(const Dataset& batch, const std::string& part, double step_cpu,
                             double draw_cpu) {
  if (!options_.cost_reference || step_state_.shard.active()) return;
  if (!reference_) {
    reference_ = options_.cost_reference();
    reference_cache_ = network_.new_cache();
  }
  if (part == reference_->id()) return;
  TrainingSummary::Phase& phase = summary_.phases.back();
  // Every step counts toward the part's cost; only the reference is sampled, whose steps cost
  // the same. (Timing the rule only at the probed steps would favour its long steps: a step
  // that pushes the training time past the probes' share is more likely a long one.)
  ++phase.timed_steps;
  phase.step_cpu_seconds += step_cpu;
  const bool first_of_part = phase.probes == 0 && summary_.iterations == phase.first_iteration + 1;
  if (!first_of_part && probe_seconds_ > kProbeShare * summary_.train_seconds) return;
  // The reference's own batch size: the step's samples, cut short or repeated to it.
  const Index count =
      options_.cost_reference_batch > 0 ? options_.cost_reference_batch : batch.size();
  Dataset resized;
  if (count != batch.size()) {
    std::vector<Index> samples(static_cast<std::size_t>(count));
    for (Index i = 0; i < count; ++i) samples[static_cast<std::size_t>(i)] = i % batch.size();
    resized = batch.select(samples);
  }
  const Dataset& reference_batch = count != batch.size() ? resized : batch;
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_seconds();
  try {
    const BatchState evaluated = evaluate_batch(network_, problem_, reference_batch,
                                                reference_->need(), *reference_cache_);
    reference_->step(evaluated);  // its Δθ is timed, never applied
  } catch (const StopRequested&) {
    // The step is applied and counted: the stop is taken at the next iteration boundary, where
    // the request is still pending; this probe is dropped.
    probe_seconds_ += seconds_since(start);
    return;
  }
  const double cpu = process_cpu_seconds() - cpu_start;
  probe_seconds_ += seconds_since(start);
  ++phase.probes;
  // A reference update in a run of its own would draw its batch too: its share of this draw.
  phase.reference_cpu_seconds +=
      cpu + draw_cpu * static_cast<double>(count) / static_cast<double>(batch.size());
}

void TrainingRun::stop_for_numbers(const std::string& message) {
  summary_.termination = TrainingTermination::kNumericalFailure;
  summary_.message += (summary_.message.empty() ? "" : "; then ") + message;
}

void TrainingRun::end_by_limit(TrainingTermination limit, const std::string& why) {
  if (!evaluated_ && !evaluate()) return;
  const double start = summary_.history.front().train_loss;
  const double end = summary_.history.back().train_loss;
  summary_.termination = limit;
  summary_.message = why;
  if (end > start) {
    summary_.termination = TrainingTermination::kDiverged;
    summary_.message = "reached " + to_string(limit) + " with the training loss " +
                       report_number(end) + " above its start " + report_number(start) +
                       (why.empty() ? "" : "; " + why);
  }
}

TrainingSummary TrainingRun::interrupted(std::string message) {
  checkpoint();
  summary_.termination = TrainingTermination::kInterrupted;
  summary_.message = std::move(message);
  return summary_;
}

}  // namespace training

TrainingSummary train(Network& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& train_set, const Dataset* test_set,
                      const TrainerOptions& options) {
  check_problem(network, problem, train_set, "training set");
  if (test_set != nullptr) check_problem(network, problem, *test_set, "test set");
  training::check_trainer_options(options);
  return training::TrainingRun(network, update, problem, train_set, test_set, options).run();
}

}  // namespace physgrad
