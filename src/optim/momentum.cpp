#include "physgrad/optim/momentum.hpp"

namespace physgrad {

Momentum::Momentum(Options options) : options_(options) {
  require_positive("momentum: lr", options_.lr);
  require_in_range("momentum: beta", options_.beta, 0.0, 1.0);
}

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
