// Direct optimization of a user's nonlinear least-squares fit: a decay y(t) = a·e^(−k t) + c
// fitted to points by Gauss-Newton, L-BFGS and IG, the model differentiated by forward-mode duals.
#include <cmath>
#include <cstdio>

#include "physgrad/physgrad.hpp"

using physgrad::Index;
using physgrad::Vector;

// The model at the sample times: x = (a, k, c) ↦ (a·e^(−k tᵢ) + c)ᵢ, written once for any
// scalar type so that AutoDiffSimulator can differentiate it.
struct DecayModel {
  Vector times;

  template <typename T>
  Eigen::Matrix<T, Eigen::Dynamic, 1> operator()(const Eigen::Matrix<T, Eigen::Dynamic, 1>& x,
                                                 const Vector& /*context*/) const {
    using std::exp;
    Eigen::Matrix<T, Eigen::Dynamic, 1> y(times.size());
    for (Index i = 0; i < times.size(); ++i) y(i) = x(0) * exp(-x(1) * times(i)) + x(2);
    return y;
  }
};

int main() {
  // 25 measurements of a = 5, k = 1.3, c = 0.5 with a small deterministic disturbance.
  const Vector times = Vector::LinSpaced(25, 0.0, 4.0);
  Vector data(times.size());
  for (Index i = 0; i < times.size(); ++i) {
    data(i) = 5.0 * std::exp(-1.3 * times(i)) + 0.5 + 0.02 * std::sin(7.0 * times(i));
  }

  const physgrad::AutoDiffSimulator model(DecayModel{times}, "decay", 3, times.size());
  const physgrad::L2Loss loss;  // ½‖y − data‖²
  const physgrad::Objective objective(model, loss, data);
  // Full Gauss-Newton and IG steps need a start near the fit: from (1, 0.1, 0) they overshoot to
  // a decay rate k ≈ 75, where the model is flat in k, and stall there; lm, whose damping
  // rejects such steps, reaches the fit from there too.
  const Vector start{{1.0, 1.0, 0.0}};

  // Stop once an iteration changes the loss by at most 1e-10 of its value (Ceres' function
  // tolerance): the data are noisy, so the loss never reaches zero.
  physgrad::MinimizeOptions options;
  options.max_iterations = 500;
  options.function_tolerance = 1e-10;

  std::printf("start: loss %.6e\n", objective.value(start));
  for (const char* id : {"gn", "lbfgs", "ig"}) {
    auto optimizer = physgrad::make_optimizer(id);
    const physgrad::MinimizeSummary fit = physgrad::minimize(*optimizer, objective, start, options);
    std::printf("%-5s %3d iterations, final loss %.6e, (a, k, c) = (%.4f, %.4f, %.4f)\n", id,
                fit.iterations, fit.loss, fit.x(0), fit.x(1), fit.x(2));
  }
  return 0;
}
