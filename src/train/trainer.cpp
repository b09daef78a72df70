#include "physgrad/train/trainer.hpp"

#include <chrono>
#include <cmath>
#include <numeric>
#include <sstream>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/train/data_parallel.hpp"

namespace physgrad {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void check_problem(const Mlp& network, const LearningProblem& problem, const Dataset& data,
                   const char* name) {
  if (problem.physics == nullptr || problem.loss == nullptr) {
    throw Error("learning problem needs a simulator and a loss");
  }
  data.validate(name);
  std::ostringstream msg;
  if (data.inputs.rows() != network.input_dim()) {
    msg << name << ": inputs have " << data.inputs.rows() << " rows, the network takes "
        << network.input_dim();
  } else if (network.output_dim() != problem.physics->input_dim()) {
    msg << "the network outputs " << network.output_dim() << " values, simulator '"
        << problem.physics->name() << "' takes " << problem.physics->input_dim();
  } else if (data.targets.rows() != problem.physics->output_dim()) {
    msg << name << ": targets have " << data.targets.rows() << " rows, simulator '"
        << problem.physics->name() << "' outputs " << problem.physics->output_dim();
  } else if (data.context.size() != 0 && data.context.rows() != problem.physics->context_dim()) {
    msg << name << ": context has " << data.context.rows() << " rows, simulator '"
        << problem.physics->name() << "' expects " << problem.physics->context_dim();
  } else {
    return;
  }
  throw Error(msg.str());
}

// Per-sample losses and ∂(mean L)/∂y for a batch of outputs y.
double batch_loss(const Loss& loss, const Matrix& y, const Matrix& targets, Matrix* gradient_y) {
  const auto batch = static_cast<double>(y.cols());
  double total = 0;
  if (gradient_y != nullptr) gradient_y->resize(y.rows(), y.cols());
  for (Index i = 0; i < y.cols(); ++i) {
    const Vector yi = y.col(i), ti = targets.col(i);
    total += loss.value(yi, ti);
    if (gradient_y != nullptr) gradient_y->col(i) = loss.gradient(yi, ti) / batch;
  }
  return total / batch;
}

}  // namespace

double mean_loss(const Mlp& network, const LearningProblem& problem, const Dataset& data) {
  check_problem(network, problem, data, "data set");
  const Matrix x = network.forward(data.inputs);
  const Matrix y = problem.physics->forward_batch(x, data.context);
  return batch_loss(*problem.loss, y, data.targets, nullptr);
}

BatchState evaluate_batch(const Mlp& network, const LearningProblem& problem,
                          const Dataset& batch, UpdateNeed need, MlpCache& cache,
                          BatchTiming* timing) {
  const Simulator& physics = *problem.physics;
  auto mark = Clock::now();
  const auto lap = [&mark](double BatchTiming::*part, BatchTiming* into) {
    const auto now = Clock::now();
    if (into != nullptr) into->*part += std::chrono::duration<double>(now - mark).count();
    mark = now;
  };
  BatchState state;
  state.batch_size = batch.size();
  Matrix gradient_y;
  const Matrix x = network.forward(batch.inputs, cache);
  const Matrix y = physics.forward_batch(x, batch.context);
  state.loss = batch_loss(*problem.loss, y, batch.targets, &gradient_y);
  lap(&BatchTiming::forward, timing);

  if (need == UpdateNeed::kGradient) {
    state.gradient = network.backward(cache, physics.vjp_batch(x, batch.context, gradient_y));
  } else if (need == UpdateNeed::kNetworkOutputs) {
    state.physics = &physics;
    state.loss_function = problem.loss;
    state.x = x;
    state.y = y;
    state.targets = batch.targets;
    state.context = batch.context;
    state.backprop = [&network, &cache](const Matrix& gx) { return network.backward(cache, gx); };
  } else {
    state.jacobian = std::make_shared<const StackedJacobian>(network, cache, physics, x, batch.context);
    state.loss_gradient_y = gradient_y.transpose().reshaped();  // entry k·B + i
  }
  lap(&BatchTiming::derivatives, timing);
  return state;
}

namespace {

void check_options(const TrainerOptions& options) {
  if (options.batch_size < 1) {
    throw Error("batch size must be ≥ 1, got " + std::to_string(options.batch_size));
  }
  if (!options.max_iterations && !options.max_epochs && !options.time_budget_seconds) {
    throw Error("training needs a limit: max_iterations, max_epochs or time_budget_seconds");
  }
  if (options.max_iterations && *options.max_iterations < 1) {
    throw Error("max_iterations must be ≥ 1, got " + std::to_string(*options.max_iterations));
  }
  if (options.max_epochs && *options.max_epochs < 1) {
    throw Error("max_epochs must be ≥ 1, got " + std::to_string(*options.max_epochs));
  }
  if (options.time_budget_seconds && !(*options.time_budget_seconds > 0)) {
    throw Error("time budget must be > 0 seconds");
  }
  if (options.eval_every && *options.eval_every < 1) {
    throw Error("eval_every must be ≥ 1, got " + std::to_string(*options.eval_every));
  }
  if (options.checkpoint_every && *options.checkpoint_every < 1) {
    throw Error("checkpoint_every must be ≥ 1, got " + std::to_string(*options.checkpoint_every));
  }
  if (options.checkpoint_seconds && !(*options.checkpoint_seconds >= 0)) {
    throw Error("checkpoint_seconds must be ≥ 0");
  }
  if (options.max_step_halvings < 0) {
    throw Error("max_step_halvings must be ≥ 0, got " + std::to_string(options.max_step_halvings));
  }
}

// One training run: the loop state between iterations (what a checkpoint holds) and the steps.
class TrainingRun {
 public:
  TrainingRun(Mlp& network, LearningUpdate& update, const LearningProblem& problem,
              const Dataset& train_set, const Dataset* test_set, const TrainerOptions& options)
      : network_(network),
        update_(update),
        problem_(problem),
        train_set_(train_set),
        test_set_(test_set),
        options_(options),
        n_(train_set.size()),
        batch_size_(std::min(options.batch_size, train_set.size())),
        parallel_(options.communicator) {}

  TrainingSummary run();

 private:
  void restore(const TrainerState& state);
  // What ends training between two iterations besides the iteration limit: a stop request and
  // the time budget, agreed by all ranks of a data-parallel run (any rank's counts), so that
  // every rank stops at the same iteration.
  struct Requests {
    bool stop = false;
    bool time_out = false;
  };
  Requests requests();
  bool evaluate();
  bool step(const std::vector<Index>& batch);
  void stop_for_numbers(const std::string& message);
  bool checkpoint_due() const;
  void checkpoint();
  const char* out_of_budget(bool time_out) const;

  Mlp& network_;
  LearningUpdate& update_;
  const LearningProblem& problem_;
  const Dataset& train_set_;
  const Dataset* test_set_;
  const TrainerOptions& options_;
  const Index n_;
  const Index batch_size_;
  DataParallel parallel_;  // this process alone without a communicator

  TrainingSummary summary_;
  long long epoch_ = 0;
  Index batch_start_ = 0;
  Vector last_step_, before_last_step_, last_evaluated_;
  bool evaluated_ = false;  // θ is the one of the last history record
  MlpCache cache_;
  Clock::time_point last_checkpoint_time_ = Clock::now();
  long long last_checkpoint_iteration_ = 0;
};

TrainingSummary TrainingRun::run() {
  update_.reset();
  if (options_.resume != nullptr) {
    restore(*options_.resume);
  } else {
    evaluate();
  }
  last_checkpoint_iteration_ = summary_.iterations;
  while (summary_.termination.empty()) {
    if (batch_start_ == 0 && options_.max_epochs && epoch_ >= *options_.max_epochs) {
      summary_.termination = "max_epochs";
      break;
    }
    std::vector<Index> order(static_cast<std::size_t>(n_));
    if (options_.shuffle) {
      order = shuffled_indices(n_, options_.seed + static_cast<std::uint64_t>(epoch_));
    } else {
      std::iota(order.begin(), order.end(), Index{0});
    }
    while (batch_start_ < n_ && summary_.termination.empty()) {
      const Requests pending = requests();
      if (pending.stop) {
        checkpoint();
        summary_.termination = "interrupted";
        summary_.message = "stopped on request after iteration " +
                           std::to_string(summary_.iterations);
        return summary_;
      }
      if (checkpoint_due()) checkpoint();
      if (const char* reason = out_of_budget(pending.time_out)) {
        summary_.termination = reason;
        break;
      }
      const Index count = std::min(batch_size_, n_ - batch_start_);
      const auto first = order.begin() + batch_start_;
      if (!step(std::vector<Index>(first, first + count))) break;
      batch_start_ += batch_size_;
      if (options_.eval_every && summary_.iterations % *options_.eval_every == 0) evaluate();
    }
    if (!summary_.termination.empty()) break;
    ++epoch_;
    batch_start_ = 0;
    if (!options_.eval_every) evaluate();
  }
  if (!evaluated_) evaluate();
  return summary_;
}

void TrainingRun::restore(const TrainerState& state) {
  const Index count = network_.num_parameters();
  const auto fits = [count](const Vector& v, bool may_be_empty) {
    return v.size() == count || (may_be_empty && v.size() == 0);
  };
  std::string problem;
  if (!fits(state.parameters, false) || !fits(state.last_evaluated, false) ||
      !fits(state.last_step, true) || state.before_last_step.size() != state.last_step.size()) {
    problem = "its vectors do not have the network's " + std::to_string(count) + " weights";
  } else if (state.epoch < 0 || state.batch_start < 0 || state.batch_start >= n_ ||
             state.batch_start % batch_size_ != 0) {
    problem = "epoch " + std::to_string(state.epoch) + ", batch start " +
              std::to_string(state.batch_start) + " do not fit " + std::to_string(n_) +
              " samples in batches of " + std::to_string(batch_size_);
  } else if (state.summary.history.empty() || !state.summary.termination.empty()) {
    problem = "it has no history or belongs to a finished run";
  }
  if (!problem.empty()) throw Error("cannot resume training from this state: " + problem);
  network_.set_parameters(state.parameters);
  update_.restore(state.update_state, count);
  summary_ = state.summary;
  epoch_ = state.epoch;
  batch_start_ = state.batch_start;
  last_step_ = state.last_step;
  before_last_step_ = state.before_last_step;
  last_evaluated_ = state.last_evaluated;
  evaluated_ = summary_.history.back().iteration == summary_.iterations &&
               network_.parameters() == last_evaluated_;
}

// Records the losses of the current θ. A non-finite loss stops training with θ restored to the
// last evaluated parameters (the untrained network's is an Error: nothing to go back to).
bool TrainingRun::evaluate() {
  TrainingRecord record;
  record.iteration = summary_.iterations;
  record.epoch =
      static_cast<double>(summary_.iterations * batch_size_) / static_cast<double>(n_);
  record.train_seconds = summary_.train_seconds;
  record.train_loss = parallel_.mean_loss(network_, problem_, train_set_);
  record.test_loss = test_set_ ? parallel_.mean_loss(network_, problem_, *test_set_) : NAN;
  const char* bad = !std::isfinite(record.train_loss)                       ? "train"
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
  summary_.history.push_back(record);
  last_evaluated_ = network_.parameters();
  evaluated_ = true;
  if (options_.on_progress) options_.on_progress(record);
  return true;
}

// One update on the samples `batch` under the numerical guard; false when training must stop.
// Every rank of a data-parallel run sees the same combined numbers and takes the same branches.
bool TrainingRun::step(const std::vector<Index>& batch) {
  const auto step_start = Clock::now();
  UpdateStep step;
  const char* failure = nullptr;
  int halvings = 0;
  for (;;) {
    BatchTiming timing;
    const BatchState state =
        parallel_.evaluate(network_, problem_, train_set_, batch, update_.need(), cache_, &timing);
    summary_.forward_seconds += timing.forward;
    summary_.derivative_seconds += timing.derivatives;
    failure = !std::isfinite(state.loss)            ? "loss"
              : !all_finite(state.gradient)         ? "gradient"
              : !all_finite(state.loss_gradient_y)  ? "loss gradient"
                                                    : nullptr;
    const auto update_start = Clock::now();
    if (failure == nullptr) {
      step = parallel_.step(update_, state);
      summary_.inversion_seconds += step.inversion_seconds;
      summary_.derivative_seconds += step.jacobian_seconds;
      if (!all_finite(step.delta)) failure = "update";
    }
    if (failure == nullptr) {
      summary_.update_seconds +=
          seconds_since(update_start) - step.inversion_seconds - step.jacobian_seconds;
      break;
    }
    // The batch at θ is broken. If θ came from a step that can be halved, try half of it.
    if (!update_.steps_can_be_halved() || last_step_.size() == 0 ||
        halvings == options_.max_step_halvings) {
      break;
    }
    last_step_ *= 0.5;
    network_.parameters() = before_last_step_ + last_step_;
    ++halvings;
    ++summary_.step_halvings;
  }
  if (failure != nullptr) {
    // A non-finite step is never applied. A non-finite loss or derivative means the last
    // applied step already broke θ: it is undone, back to the θ whose batch was finite.
    const bool undo = last_step_.size() != 0 && (std::string(failure) != "update" || halvings > 0);
    if (undo) {
      network_.set_parameters(before_last_step_);
      evaluated_ = false;
    }
    const std::string it = std::to_string(summary_.iterations);
    stop_for_numbers(
        std::string("non-finite ") + failure + " at iteration " +
        std::to_string(summary_.iterations + 1) +
        (halvings > 0 ? ", also after halving update " + it + " " + std::to_string(halvings) +
                            " times"
                      : std::string()) +
        (undo ? "; update " + it + " undone, parameters restored to those before it"
              : std::string("; the step was not applied")));
    return false;
  }
  before_last_step_ = network_.parameters();
  last_step_ = std::move(step.delta);
  network_.parameters() += last_step_;
  evaluated_ = false;
  summary_.train_seconds += seconds_since(step_start);
  ++summary_.iterations;
  return true;
}

void TrainingRun::stop_for_numbers(const std::string& message) {
  summary_.termination = "numerical_failure";
  summary_.message += (summary_.message.empty() ? "" : "; then ") + message;
}

TrainingRun::Requests TrainingRun::requests() {
  double flags[2] = {
      options_.stop != nullptr && options_.stop->load() ? 1.0 : 0.0,
      options_.time_budget_seconds && summary_.train_seconds >= *options_.time_budget_seconds
          ? 1.0
          : 0.0};
  if (parallel_.active()) parallel_.communicator()->allreduce_sum(flags, 2);
  return {flags[0] > 0, flags[1] > 0};
}

bool TrainingRun::checkpoint_due() const {
  if (!options_.on_checkpoint || summary_.iterations == last_checkpoint_iteration_) return false;
  return (options_.checkpoint_every && summary_.iterations % *options_.checkpoint_every == 0) ||
         (options_.checkpoint_seconds &&
          seconds_since(last_checkpoint_time_) >= *options_.checkpoint_seconds);
}

void TrainingRun::checkpoint() {
  if (options_.on_checkpoint) {
    TrainerState state;
    state.epoch = epoch_;
    state.batch_start = batch_start_;
    state.parameters = network_.parameters();
    state.last_step = last_step_;
    state.before_last_step = before_last_step_;
    state.last_evaluated = last_evaluated_;
    state.update_state = update_.state();
    state.summary = summary_;
    options_.on_checkpoint(state);
  }
  last_checkpoint_time_ = Clock::now();
  last_checkpoint_iteration_ = summary_.iterations;
}

const char* TrainingRun::out_of_budget(bool time_out) const {
  if (options_.max_iterations && summary_.iterations >= *options_.max_iterations) {
    return "max_iterations";
  }
  return time_out ? "time_budget" : nullptr;
}

}  // namespace

TrainingSummary train(Mlp& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& train_set, const Dataset* test_set,
                      const TrainerOptions& options) {
  check_problem(network, problem, train_set, "training set");
  if (test_set != nullptr) check_problem(network, problem, *test_set, "test set");
  check_options(options);
  return TrainingRun(network, update, problem, train_set, test_set, options).run();
}

}  // namespace physgrad
