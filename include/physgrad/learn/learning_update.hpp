// LearningUpdate — one update rule for network weights θ trained through a simulator: it declares
// what it needs of a mini-batch (∇θ, the stacked Jacobian, or the network outputs) and returns Δθ.
#pragma once

#include <cmath>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/learn/stacked_jacobian.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/simulator.hpp"
#include "physgrad/rule_step.hpp"

namespace physgrad {

enum class UpdateNeed {
  kGradient,         // ∇θ of the batch-mean loss
  kStackedJacobian,  // J = ∂(y₁…y_B)/∂θ stacked over samples and outputs, and ∂(mean L)/∂y
  kNetworkOutputs,   // x = f(in; θ), y = P(x), the batch's targets and context, and a backprop
                     // that maps a cotangent at x to ∇θ (for updates that build their own
                     // loss in x, such as SIP)
  kWeightedFactors,  // ∇θ as kGradient, and the network's dense-layer factors over the output
                     // cotangents (∂P/∂x)ᵀ w of weights w on the physics outputs the rule gives
};

// What evaluate_batch() computed for one mini-batch; only the fields the update needs are
// filled. J and ∂L/∂y share one row order (output-major: row k·B + i for sample i, output k).
// In a data-parallel run the sample-wise fields (x, y, targets, context) hold this rank's share
// and batch_size the whole batch; everything else is the same on every rank.
struct BatchState {
  Index batch_size = 0;
  double loss = 0;          // mean per-sample loss over the batch
  Vector gradient;          // ∇θ (mean loss)                          [kGradient]
  std::shared_ptr<const StackedJacobian> jacobian;  //                  [kStackedJacobian]
  Vector loss_gradient_y;   // B·m, entry k·B + i = ∂(mean L)/∂y_ik    [kStackedJacobian]
  // [kNetworkOutputs]
  const Simulator* physics = nullptr;
  const Loss* loss_function = nullptr;
  Matrix x, y, targets, context;                  // one sample per column
  std::function<Vector(const Matrix&)> backprop;  // cotangent at x (n × B) ↦ ∇θ
  // [kWeightedFactors] m, and the factors of each dense layer (DenseLayerFactors) over the
  // cotangents (∂P/∂x_i)ᵀ W_c.col(i) of every given weight matrix W_c (m × B, column i for sample
  // i): one batched physics VJP and one backward sweep per matrix, never the B·m rows of J.
  Index outputs = 0;
  std::function<std::vector<DenseLayerFactors>(const std::vector<Matrix>&)> weighted_factors;
};

// What the trainer tells a rule after each evaluation of the network (the untrained one
// included): the losses over the training and test sets after `iteration` updates.
struct Evaluation {
  long long iteration = 0;
  double train_loss = 0;
  double test_loss = NAN;  // NaN without a test set
};

class LearningUpdate {
 public:
  virtual ~LearningUpdate() = default;
  virtual std::string id() const = 0;
  // The id of the rule making the updates now: id(), or a rule made of parts its current part's.
  virtual std::string part_id() const { return id(); }
  // Every setting that distinguishes a run, for config and summary files.
  virtual nlohmann::json params() const = 0;
  virtual UpdateNeed need() const = 0;
  // Forget the state of a run (moments); train() calls it before the first step.
  virtual void reset() {}
  // Δθ for the batch. Numerical trouble may surface as a non-finite Δθ or a NumericalError;
  // train_step() turns both into a stopped run, never into a changed θ.
  // Step::status stays kOk; Step::message says why delta is not finite, when the rule knows.
  virtual Step step(const BatchState& batch) = 0;
  // The step size η, readable and settable between steps (a schedule in one's own loop).
  virtual double learning_rate() const = 0;
  virtual void set_learning_rate(double lr) = 0;
  // The state carried between steps (null for stateless rules), and its restoration for a
  // network with `parameter_count` weights; throws Error on a malformed state.
  virtual nlohmann::json state() const { return nullptr; }
  virtual void restore(const nlohmann::json& /*state*/, Index /*parameter_count*/) {}
  // True when a step may be scaled down after the fact without changing the rule's state, so a
  // step that leads to a non-finite batch can be retried at half its length.
  virtual bool steps_can_be_halved() const { return false; }
  // What the last step did beyond Δθ, as named numbers and words for the metrics of an
  // evaluation (hig: the inversion's path, kept directions, …); empty when there is nothing.
  virtual nlohmann::json step_info() const { return nlohmann::json::object(); }

  // Called after every evaluation, in order (every rank of a data-parallel run sees the same
  // numbers): a rule that schedules its step size or switches on the evaluated loss reads it.
  virtual void observe(const Evaluation& /*evaluation*/) {}
  // A rule made of parts in turn (SwitchingUpdate): the part that makes the next step, from 0.
  // When it changes the trainer evaluates the network and starts a new epoch.
  virtual int phase() const { return 0; }
  // The mini-batch size the part making the next step was given; unset: the trainer's.
  virtual std::optional<Index> batch_size() const { return std::nullopt; }
};

}  // namespace physgrad
