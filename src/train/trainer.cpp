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

TrainingSummary train(Mlp& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& train_set, const Dataset* test_set,
                      const TrainerOptions& options) {
  check_problem(network, problem, train_set, "training set");
  if (test_set != nullptr) check_problem(network, problem, *test_set, "test set");
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

  const Index n = train_set.size();
  const Index batch_size = std::min(options.batch_size, n);
  TrainingSummary summary;
  update.reset();
  DataParallel parallel(options.communicator);  // this process alone without a communicator

  const auto evaluate = [&] {
    TrainingRecord record;
    record.iteration = summary.iterations;
    record.epoch = static_cast<double>(summary.iterations * batch_size) / static_cast<double>(n);
    record.train_seconds = summary.train_seconds;
    record.train_loss = parallel.mean_loss(network, problem, train_set);
    record.test_loss = test_set ? parallel.mean_loss(network, problem, *test_set) : NAN;
    if (options.on_evaluate) options.on_evaluate(network, record);
    summary.history.push_back(record);
    if (options.on_progress) options.on_progress(record);
  };
  const auto out_of_budget = [&]() -> const char* {
    if (options.max_iterations && summary.iterations >= *options.max_iterations) {
      return "max_iterations";
    }
    if (options.time_budget_seconds && summary.train_seconds >= *options.time_budget_seconds) {
      return "time_budget";
    }
    return nullptr;
  };

  evaluate();
  MlpCache cache;
  Vector before_last_step;  // θ before the last applied update
  bool undone = false;      // that update was undone after a non-finite batch
  long long epoch = 0;
  while (summary.termination.empty()) {
    if (options.max_epochs && epoch >= *options.max_epochs) {
      summary.termination = "max_epochs";
      break;
    }
    std::vector<Index> order(static_cast<std::size_t>(n));
    if (options.shuffle) {
      order = shuffled_indices(n, options.seed + static_cast<std::uint64_t>(epoch));
    } else {
      std::iota(order.begin(), order.end(), Index{0});
    }
    for (Index start = 0; start < n && summary.termination.empty(); start += batch_size) {
      if (const char* reason = out_of_budget()) {
        summary.termination = reason;
        break;
      }
      const Index count = std::min(batch_size, n - start);
      const std::vector<Index> indices(order.begin() + start, order.begin() + start + count);

      const auto step_start = Clock::now();
      BatchTiming timing;
      const BatchState batch =
          parallel.evaluate(network, problem, train_set, indices, update.need(), cache, &timing);
      summary.forward_seconds += timing.forward;
      summary.derivative_seconds += timing.derivatives;
      const char* failure = !std::isfinite(batch.loss)                 ? "loss"
                            : !all_finite(batch.gradient)                ? "gradient"
                            : !all_finite(batch.loss_gradient_y)         ? "loss gradient"
                                                                         : nullptr;
      const auto update_start = Clock::now();
      UpdateStep step;
      if (failure == nullptr) {
        step = parallel.step(update, batch);
        summary.inversion_seconds += step.inversion_seconds;
        summary.derivative_seconds += step.jacobian_seconds;
        if (!all_finite(step.delta)) failure = "update";
      }
      if (failure != nullptr) {
        // A non-finite step is never applied. A non-finite loss or derivative means the last
        // applied step already broke θ: it is undone, back to the θ whose batch was finite.
        undone = step.delta.size() == 0 && summary.iterations > 0;
        if (undone) network.set_parameters(before_last_step);
        summary.termination = "numerical_failure";
        summary.message = std::string("non-finite ") + failure + " at iteration " +
                          std::to_string(summary.iterations + 1) +
                          (undone ? "; update " + std::to_string(summary.iterations) +
                                      " undone, parameters restored to those before it"
                                : std::string("; the step was not applied"));
        break;
      }
      before_last_step = network.parameters();
      network.parameters() += step.delta;
      summary.update_seconds +=
          seconds_since(update_start) - step.inversion_seconds - step.jacobian_seconds;
      summary.train_seconds += seconds_since(step_start);
      ++summary.iterations;
      if (options.eval_every && summary.iterations % *options.eval_every == 0) evaluate();
    }
    ++epoch;
    if (!options.eval_every && summary.termination.empty()) evaluate();
  }
  if (undone || summary.history.back().iteration != summary.iterations) evaluate();
  return summary;
}

}  // namespace physgrad
