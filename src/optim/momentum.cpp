#include "physgrad/optim/momentum.hpp"

namespace physgrad {

Momentum::Momentum(Options options) : options_(options) {
  require_positive("momentum: lr", options_.lr);
  require_in_range("momentum: beta", options_.beta, 0.0, 1.0);
}

Step Momentum::step(const Objective& objective, const Vector& x) {
  const Vector g = objective.gradient(x);
  if (velocity_.size() != g.size()) velocity_ = Vector::Zero(g.size());
  velocity_ = options_.beta * velocity_ + g;
  return {-options_.lr * velocity_, Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
