#include "physgrad/optim/gradient_descent.hpp"

namespace physgrad {

GradientDescent::GradientDescent(Options options) : options_(options) {
  require_positive("gd: lr", options_.lr);
}

Step GradientDescent::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  // Δz = −η ∇_z L = −η D g, so Δx = D Δz = −η D² g; then projected onto the box.
  const Vector s = domain.scale(x.size());
  const Vector dx = -options_.lr * s.cwiseAbs2().cwiseProduct(objective.gradient(x));
  return {domain.feasible_step(x, dx), Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
