// The small learning problem the learning tests share: a 2 → 6 → 2 tanh network in front of the
// nonlinear comparison function P(x) = (x₀, x₁²) with reachable targets.
#pragma once

#include <cmath>

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
    data.inputs.resize(2, n);
    Matrix x_star(2, n);
    for (Index j = 0; j < n; ++j) {
      const double u = std::sin(1.3 * static_cast<double>(j));
      const double v = std::cos(0.7 * static_cast<double>(j));
      data.inputs.col(j) << u, v;
      x_star.col(j) << std::sin(2 * u), std::cos(3 * v);
    }
    data.targets = physics.forward_batch(x_star, Matrix());
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

}  // namespace physgrad::testing
