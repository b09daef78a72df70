#include "physgrad/optim/gradient_descent.hpp"

namespace physgrad {

const OptionList<GradientDescentOptions>& GradientDescentOptions::descriptors() {
  static const OptionList<GradientDescentOptions> options = {
      rule_option("lr", &GradientDescentOptions::lr, positive(), "step size η"),
  };
  return options;
}

GradientDescent::GradientDescent(Options options) : options_(checked("gd", options)) {}

Step GradientDescent::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  // Δz = −η ∇_z L = −η D g, so Δx = D Δz = −η D² g; then projected onto the box.
  const Vector s = domain.scale(x.size());
  const Vector dx = -options_.lr * s.cwiseAbs2().cwiseProduct(objective.gradient(x));
  return {domain.feasible_step(x, dx), Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
