// Trainer — minimizes mean_i L(P(f(inᵢ; θ); cᵢ), yᵢ*) over mini-batches with a LearningUpdate,
// computing exactly what the update needs (∇θ by backprop, or the stacked Jacobian by m VJPs).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "physgrad/loss/loss.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/optim/learning_update.hpp"
#include "physgrad/parallel/communicator.hpp"
#include "physgrad/physics/simulator.hpp"
#include "physgrad/train/dataset.hpp"

namespace physgrad {

// The physics after the network and the per-sample loss on its output.
struct LearningProblem {
  const Simulator* physics = nullptr;
  const Loss* loss = nullptr;
};

struct TrainingRecord {
  long long iteration = 0;   // updates made so far
  double epoch = 0;          // iteration·B / N (fractional)
  double train_seconds = 0;  // training time so far, evaluations excluded
  double train_loss = 0;     // mean loss over the training set
  double test_loss = 0;      // mean loss over the test set (NaN without one)
  nlohmann::json extras = nlohmann::json::object();  // filled by TrainerOptions::on_evaluate
};

struct TrainerOptions {
  Index batch_size = 32;
  // Stop after any of these; at least one must be set.
  std::optional<long long> max_iterations;
  std::optional<long long> max_epochs;
  std::optional<double> time_budget_seconds;  // training time, evaluations excluded
  // Evaluate every this many iterations; unset: at the start and after every epoch.
  std::optional<long long> eval_every;
  bool shuffle = true;
  std::uint64_t seed = 0;  // shuffling order
  // Data-parallel training: the ranks of this communicator share every mini-batch (see
  // train/data_parallel.hpp); none, or one rank: this process alone.
  std::shared_ptr<Communicator> communicator;
  // Adds experiment-specific figures to a record at each evaluation.
  std::function<void(const Mlp&, TrainingRecord&)> on_evaluate;
  // Progress line after each evaluation.
  std::function<void(const TrainingRecord&)> on_progress;
};

struct TrainingSummary {
  std::vector<TrainingRecord> history;  // history[0] is the untrained network
  std::string termination;              // "max_iterations", "max_epochs", "time_budget",
                                        // "numerical_failure"
  std::string message;
  long long iterations = 0;
  double train_seconds = 0;
  // Time per part of all steps: network+physics forward and loss, the stacked Jacobian or
  // gradient, the inversion inside the update, and the rest of the update.
  double forward_seconds = 0;
  double derivative_seconds = 0;
  double inversion_seconds = 0;
  double update_seconds = 0;
};

// Mean loss of the network over a data set.
double mean_loss(const Mlp& network, const LearningProblem& problem, const Dataset& data);

// Seconds spent in the parts of evaluate_batch(), accumulated.
struct BatchTiming {
  double forward = 0;      // network, physics and loss
  double derivatives = 0;  // ∇θ by backprop, or the stacked Jacobian
};

// Computes for one mini-batch exactly what `need` asks for: the mean loss and ∇θ by one
// backward pass through physics and network; or the stacked Jacobian (row k·B + i =
// ∂y_ik/∂θ) as a StackedJacobian after one batched VJP per physics output k, with
// ∂(mean L)/∂y in the same order (the update forms J or J Jᵀ as it needs); or the network
// outputs and a backprop. `cache` is reused between calls and must outlive the returned state.
BatchState evaluate_batch(const Mlp& network, const LearningProblem& problem,
                          const Dataset& batch, UpdateNeed need, MlpCache& cache,
                          BatchTiming* timing = nullptr);

// Trains `network` in place. Throws Error on mismatched dimensions or invalid options. A NaN/Inf
// loss, derivative or step stops training with termination "numerical_failure": a non-finite
// step is never applied, and when the loss or derivative of a batch is non-finite the update
// that led there is undone, so θ ends where every batch so far evaluated finite.
TrainingSummary train(Mlp& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& train_set, const Dataset* test_set,
                      const TrainerOptions& options);

}  // namespace physgrad
