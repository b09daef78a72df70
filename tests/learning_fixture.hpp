// The small learning problem the learning tests share: a 2 → 6 → 2 tanh network in front of the
// nonlinear comparison function P(x) = (x₀, x₁²) with reachable targets.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <utility>

#include "physgrad/catalogue.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/physics/comparison_toy.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad::testing {

struct NetworkThroughPhysics {
  ComparisonToy physics;
  L2Loss loss{1.0};
  LearningProblem problem{&physics, &loss};
  Mlp network{{2, 6, 2}, Activation::kTanh};
  Dataset data;

  // Targets y* = P(x*) with x* = (sin 2u, cos 3v) of the input (u, v).
  explicit NetworkThroughPhysics(Index n = 5) {
    network.initialize(3);
    Matrix inputs(2, n);
    for (Index j = 0; j < n; ++j) {
      inputs.col(j) << std::sin(1.3 * static_cast<double>(j)), std::cos(0.7 * static_cast<double>(j));
    }
    data = samples(inputs);
  }

  // The samples of the inputs (u, v) given, one per column.
  Dataset samples(const Matrix& inputs) const {
    Matrix x_star(2, inputs.cols());
    for (Index j = 0; j < inputs.cols(); ++j) {
      x_star.col(j) << std::sin(2 * inputs(0, j)), std::cos(3 * inputs(1, j));
    }
    return {inputs, physics.forward_batch(x_star, Matrix()), Matrix()};
  }

  // `count` samples with inputs uniform in [−1, 1)² from random stream `stream` (a SampleSource).
  Dataset draw(std::uint64_t stream, Index count) const {
    std::mt19937_64 engine(stream);
    Matrix inputs(2, count);
    for (Index k = 0; k < inputs.size(); ++k) {
      inputs.data()[k] = -1 + 2 * static_cast<double>(engine() >> 11) * 0x1.0p-53;
    }
    return samples(inputs);
  }

  // Stacked outputs y(θ) in the trainer's order (entry k·B + i).
  Vector stacked_outputs(const Vector& theta) const {
    Mlp copy = network;
    copy.set_parameters(theta);
    const Matrix y = physics.forward_batch(copy.forward(data.inputs), data.context);
    return y.transpose().reshaped();
  }

  // evaluate_batch() of the whole data set at the network's θ.
  BatchState evaluate(UpdateNeed need, MlpCache& cache) const {
    return evaluate_batch(network, problem, data, need, cache);
  }
};

// The settings the learning tests train gn and hig, and the rules that approximate them, with
// (their default η = 1 overshoots here).
inline RuleSettings test_settings(const std::string& id) {
  RuleSettings settings;
  const std::string source = settings_source(id);
  if (source == "gn" || source == "hig") settings["lr"] = 0.1;
  return settings;
}

// Adam whose k-th step (k = 0, 1, …) first calls delay(k): a rule whose steps take longer, all
// of them or some (as one that refreshes costly factors every few steps).
class AdamWithDelay final : public LearningUpdate {
 public:
  explicit AdamWithDelay(std::function<void(long long)> delay)
      : adam_(make_learning_update("adam")), delay_(std::move(delay)) {}
  std::string id() const override { return "adam-with-delay"; }
  nlohmann::json params() const override { return adam_->params(); }
  UpdateNeed need() const override { return adam_->need(); }
  void reset() override { adam_->reset(); }
  Step step(const BatchState& batch) override {
    delay_(steps_++);
    return adam_->step(batch);
  }
  double learning_rate() const override { return adam_->learning_rate(); }
  void set_learning_rate(double lr) override { adam_->set_learning_rate(lr); }

 private:
  std::unique_ptr<LearningUpdate> adam_;
  std::function<void(long long)> delay_;
  long long steps_ = 0;
};

}  // namespace physgrad::testing
