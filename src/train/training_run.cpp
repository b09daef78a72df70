// TrainingRun's bookkeeping: where the data order stands, resuming from a checkpoint, taking
// one, the requests all ranks agree on, what ran, and the options' checks.
#include <algorithm>
#include <chrono>
#include <optional>
#include <string>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/stop.hpp"
#include "physgrad/timing.hpp"
#include "training_run.hpp"

namespace physgrad {
namespace training {

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
}

std::pair<long long, Index> TrainingRun::position(long long iterations) const {
  long long epoch = 0;
  for (std::size_t p = 0; p < summary_.phases.size(); ++p) {
    const TrainingSummary::Phase& phase = summary_.phases[p];
    const long long per_epoch = (n_ + phase.batch_size - 1) / phase.batch_size;
    const bool last = p + 1 == summary_.phases.size();
    if (last || iterations < summary_.phases[p + 1].first_iteration) {
      const long long made = iterations - phase.first_iteration;
      return {epoch + made / per_epoch, (made % per_epoch) * phase.batch_size};
    }
    const long long made = summary_.phases[p + 1].first_iteration - phase.first_iteration;
    epoch += (made + per_epoch - 1) / per_epoch;
  }
  return {epoch, 0};
}

void TrainingRun::restore(const TrainerState& state) {
  const Index count = network_.num_parameters();
  const auto fits = [count](const Vector& v, bool may_be_empty) {
    return v.size() == count || (may_be_empty && v.size() == 0);
  };
  const long long iterations = state.summary.iterations;
  // A state of an earlier version has no parts: the run's one rule made every update.
  const std::vector<TrainingSummary::Phase> phases =
      state.summary.phases.empty() ? summary_.phases : state.summary.phases;
  std::string problem;
  if (!fits(state.parameters, false) || !fits(state.last_evaluated, false) ||
      !fits(state.last_step, true) || state.before_last_step.size() != state.last_step.size()) {
    problem = "its vectors do not have the network's " + std::to_string(count) + " weights";
  } else if (state.summary.history.empty() || state.summary.termination) {
    problem = "it has no history or belongs to a finished run";
  } else if (phases.front().first_iteration != 0) {
    problem = "its parts do not begin at iteration 0";
  }
  if (problem.empty()) {
    for (std::size_t p = 0; p < phases.size() && problem.empty(); ++p) {
      const TrainingSummary::Phase& phase = phases[p];
      if (phase.batch_size < 1 || phase.batch_size > n_ || phase.first_iteration > iterations ||
          (p > 0 && phase.first_iteration < phases[p - 1].first_iteration)) {
        problem = "part " + std::to_string(p + 1) + " (from iteration " +
                  std::to_string(phase.first_iteration) + ", batches of " +
                  std::to_string(phase.batch_size) + ") does not fit " + std::to_string(n_) +
                  " samples and " + std::to_string(iterations) + " iterations";
      }
    }
  }
  if (problem.empty()) {
    summary_.phases = phases;
    if (position(iterations) != std::make_pair(state.epoch, state.batch_start)) {
      // The position follows from the count and the parts (position()).
      problem = "epoch " + std::to_string(state.epoch) + " and batch start " +
                std::to_string(state.batch_start) + " do not follow from its " +
                std::to_string(iterations) + " iterations in batches of " +
                std::to_string(phases.back().batch_size) + " of " +
                std::to_string(n_) + " samples";
    }
  }
  if (!problem.empty()) throw Error("cannot resume training from this state: " + problem);
  network_.set_parameters(state.parameters);
  update_.restore(state.update_state, count);
  if (update_.phase() + 1 != static_cast<int>(phases.size())) {
    throw Error("cannot resume training from this state: the rule is in part " +
                std::to_string(update_.phase() + 1) + ", the run's record in part " +
                std::to_string(phases.size()));
  }
  summary_ = state.summary;
  summary_.phases = phases;
  phase_ = update_.phase();
  batch_size_ = summary_.phases.back().batch_size;
  epoch_ = state.epoch;
  batch_start_ = state.batch_start;
  step_state_.last_step = state.last_step;
  step_state_.before_last_step = state.before_last_step;
  // The last step was made by the current part unless that part has made none yet (a step that
  // would have been halvable had a part's rule made it; train_step() records it so).
  step_state_.last_step_halvable = iterations > summary_.phases.back().first_iteration &&
                                   update_.steps_can_be_halved();
  last_evaluated_ = state.last_evaluated;
  evaluated_ = summary_.history.back().iteration == summary_.iterations &&
               network_.parameters() == last_evaluated_;
}

TrainingRun::Requests TrainingRun::requests() const {
  const bool evaluation_due =
      options_.eval_seconds && !evaluated_ &&
      summary_.train_seconds - summary_.history.back().train_seconds >= *options_.eval_seconds;
  // A run makes at least one update; after that the budget bounds its wall time.
  bool time_out = false, overrun = false;
  const double spent = wall_now();
  if (options_.time_budget_seconds && summary_.iterations > 0) {
    const double budget = *options_.time_budget_seconds;
    const double due_before = (evaluation_due ? evaluation_cost_ : 0.0) +
                              (checkpoint_due() ? checkpoint_cost_ : 0.0);
    time_out = spent >= budget;
    overrun = !time_out && step_cost_ > 0 && spent + next_step_cost(due_before) > budget;
  }
  double flags[4] = {
      (options_.stop != nullptr && options_.stop->load()) || stop_requested() ? 1.0 : 0.0,
      time_out ? 1.0 : 0.0, overrun ? 1.0 : 0.0, evaluation_due ? 1.0 : 0.0};
  step_state_.shard.sum(flags, 4);
  return {flags[0] > 0, flags[1] > 0, flags[2] > 0 && !(flags[1] > 0), flags[3] > 0, spent};
}

double TrainingRun::next_step_cost(double due_before) const {
  const long long next = summary_.iterations + 1;
  const bool checkpoint_after = options_.on_checkpoint && options_.checkpoint_every &&
                                next % *options_.checkpoint_every == 0;
  return due_before + step_cost_ + evaluation_cost_ + (checkpoint_after ? checkpoint_cost_ : 0.0);
}

bool TrainingRun::checkpoint_due() const {
  if (!options_.on_checkpoint || summary_.iterations == last_checkpoint_iteration_) return false;
  // A run limited by time spends at most a tenth of its wall time on checkpoints: the next one
  // waits until nine times the last one's cost has passed since it.
  constexpr double kCheckpointShare = 0.1;
  const double since = seconds_since(last_checkpoint_time_);
  if (options_.time_budget_seconds &&
      checkpoint_cost_ > kCheckpointShare * (checkpoint_cost_ + since)) {
    return false;
  }
  return (options_.checkpoint_every && summary_.iterations % *options_.checkpoint_every == 0) ||
         (options_.checkpoint_seconds && since >= *options_.checkpoint_seconds);
}

void TrainingRun::describe_run() {
  summary_.update = update_.id();
  summary_.params = update_.params();
  summary_.parameters = network_.num_parameters();
  summary_.samples = n_;
  summary_.fresh_samples = static_cast<bool>(options_.fresh_samples);
  summary_.limits.clear();
  const auto limit = [this](const char* name, const auto& value) {
    if (value) summary_.limits.emplace_back(name, static_cast<double>(*value));
  };
  limit("max_iterations", options_.max_iterations);
  limit("max_epochs", options_.max_epochs);
  limit("time_budget_seconds", options_.time_budget_seconds);
}

void TrainingRun::checkpoint() {
  const auto start = std::chrono::steady_clock::now();
  summary_.wall_seconds = wall_now();
  if (options_.on_checkpoint) {
    TrainerState state;
    state.epoch = epoch_;
    state.batch_start = batch_start_;
    state.parameters = network_.parameters();
    state.last_step = step_state_.last_step;
    state.before_last_step = step_state_.before_last_step;
    state.last_evaluated = last_evaluated_;
    state.update_state = update_.state();
    state.summary = summary_;
    options_.on_checkpoint(state);
  }
  checkpoint_cost_ = seconds_since(start);
  last_checkpoint_time_ = std::chrono::steady_clock::now();
  last_checkpoint_iteration_ = summary_.iterations;
}

}  // namespace training

std::uint64_t fresh_stream(std::uint64_t seed, long long iterations) {
  // splitmix64's finaliser over the seed, then over the seed's mix and the iteration: distinct
  // inputs give distinct streams (each step is a bijection of 64-bit words).
  const auto mix = [](std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  };
  return mix(mix(seed + 0x9e3779b97f4a7c15ULL) + static_cast<std::uint64_t>(iterations));
}

}  // namespace physgrad
