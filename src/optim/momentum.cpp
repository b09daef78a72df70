#include "physgrad/optim/momentum.hpp"

namespace physgrad {

const OptionList<MomentumOptions>& MomentumOptions::descriptors() {
  static const OptionList<MomentumOptions> options = {
      rule_option("lr", &MomentumOptions::lr, positive(), "step size η"),
      rule_option("beta", &MomentumOptions::beta, fraction(), "momentum β (0: gradient descent)"),
  };
  return options;
}

Momentum::Momentum(Options options) : options_(checked("momentum", options)) {}

Step Momentum::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  // The velocity lives in z: v ← βv + D g, Δx = −η D v, projected onto the box.
  const Vector s = domain.scale(x.size());
  const Vector gz = s.cwiseProduct(objective.gradient(x));
  if (velocity_.size() != gz.size()) velocity_ = Vector::Zero(gz.size());
  velocity_ = options_.beta * velocity_ + gz;
  return {domain.feasible_step(x, -options_.lr * s.cwiseProduct(velocity_)), Step::Status::kOk,
          {}, 1};
}

}  // namespace physgrad
