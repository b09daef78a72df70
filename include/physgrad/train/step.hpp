// One training step: evaluate a mini-batch for what a LearningUpdate needs (in a data-parallel run,
// this rank's share, combined over ranks), compute Δθ and apply it under the numerical guard.
#pragma once

#include <memory>
#include <string>

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/nn/network.hpp"
#include "physgrad/parallel/shard.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/train/dataset.hpp"

namespace physgrad {

// The physics after the network and the per-sample loss on its output:
// min_θ mean_i L(P(f(inᵢ; θ); cᵢ), yᵢ*).
struct LearningProblem {
  const Simulator* physics = nullptr;
  const Loss* loss = nullptr;
};

// Throws Error when the problem lacks a simulator or loss, the network or the simulator has a
// dimension < 1 (CheckedNetwork, CheckedSimulator), or `data` (named `name` in the message)
// does not fit them.
void check_problem(const Network& network, const LearningProblem& problem, const Dataset& data,
                   const char* name);

// Mean loss of the network over a data set; with an active shard each rank evaluates its share
// of the samples, and the ranks also check that they hold bit-identical θ.
double mean_loss(const Network& network, const LearningProblem& problem, const Dataset& data,
                 const Shard& shard = {});

// Seconds spent in the parts of evaluate_batch(), accumulated.
struct BatchTiming {
  double forward = 0;      // network, physics and loss
  double derivatives = 0;  // ∇θ by backprop, or the physics VJPs of the stacked Jacobian
};

// Computes for the mini-batch exactly what `need` asks for: the mean loss and ∇θ by one
// backward pass through physics and network; or the stacked Jacobian (row k·B + i = ∂y_ik/∂θ)
// after one batched VJP per physics output k, with ∂(mean L)/∂y in the same order (the rule
// forms J or J Jᵀ as it needs); or the network outputs and a backprop. With an active shard
// this rank evaluates its share of the batch and the results are combined so that every rank
// holds the same loss, ∇θ, ∂L/∂y and Jacobian (a ShardedJacobian). `cache` (from the network's
// new_cache()) is reused between calls and must outlive the returned state. The network and the
// simulator are used as given: train_step() and mean_loss() hand over a CheckedNetwork and a
// CheckedSimulator, so that every size they return is checked; a caller of its own wraps them
// the same way.
BatchState evaluate_batch(const Network& network, const LearningProblem& problem,
                          const Dataset& batch, UpdateNeed need, NetworkCache& cache,
                          const Shard& shard = {}, BatchTiming* timing = nullptr);

// What train_step() keeps between calls on one network: its settings, the guard's memory of the
// last applied step and the forward cache. Start with a default one (or one with the shard and
// limit set); a checkpoint stores the two vectors.
struct StepState {
  Shard shard;  // data-parallel: the ranks that share each batch; default: this process alone
  // When the batch at θ is not finite and θ came from a step that can be halved (gn, hig),
  // that step is retried at half its length up to this many times.
  int max_step_halvings = 10;

  Vector last_step;         // the last applied Δθ (empty before the first, or after an undo)
  Vector before_last_step;  // θ before it
  bool last_step_halvable = false;  // made by a rule whose steps can be halved
  std::unique_ptr<NetworkCache> cache;
};

// What one train_step() did.
struct StepReport {
  // Where the step failed; kNone when Δθ was applied.
  enum class Failure { kNone, kLoss, kGradient, kLossGradient, kUpdate };
  Failure failure = Failure::kNone;
  std::string detail;   // what the rule or the numerics said (a NumericalError's message)
  bool undone = false;  // the previous step broke θ and was taken back
  int halvings = 0;     // times the previous step was halved before this batch
  double loss = 0;      // the batch's mean loss at θ before this update (NaN on failure)
  // Seconds per part: network+physics forward and loss, gradient or Jacobian, inversion inside
  // the rule, the rest of the rule; and the whole call.
  double forward_seconds = 0, derivative_seconds = 0, inversion_seconds = 0, update_seconds = 0;
  double total_seconds = 0;
  SimulatorCounts counts;  // the simulator's work in this step (local inverses included)

  bool applied() const { return failure == Failure::kNone; }
};
// "", "loss", "gradient", "loss gradient", "update".
std::string to_string(StepReport::Failure failure);

// One update θ ← θ + Δθ on `batch` (the whole mini-batch, also in a data-parallel run),
// torch.optim-style: call it in your own loop with any schedule, and switch rules between calls.
// Numerical guard: a non-finite loss, derivative or Δθ, or a NumericalError below the rule,
// never reaches θ. When the batch is not finite and the previous step can be halved, it is
// retried at half length (θ moves back accordingly); if that does not help, or the step cannot
// be halved, the previous step is undone (θ as before it) unless only this Δθ was bad, and the
// report says where it failed. Throws Error on mismatched dimensions (see check_problem()), and
// when the network, the simulator (both seen through CheckedNetwork and CheckedSimulator) or
// the rule returns a value of the wrong size; an exception of the network's or simulator's own
// passes through unchanged. An exception from below (a StopRequested from the simulator) leaves
// θ and `state` as they were before the call, and so the state of the library's rules, which
// change it only after their last simulator call: the step can be made again.
StepReport train_step(Network& network, LearningUpdate& update, const LearningProblem& problem,
                      const Dataset& batch, StepState& state);

// "non-finite update at iteration 4 (detail); the step was not applied", with `iteration` the
// number of updates made before this step.
std::string describe_failure(const StepReport& report, long long iteration);

}  // namespace physgrad
