#include "physgrad/optim/inverse_gradient.hpp"

namespace physgrad {

Vector y_step(const Objective& objective, const Vector& y, double lr) {
  return lr * objective.loss().newton_step(y, objective.target());
}

InverseGradient::InverseGradient(Options options) : options_(options) {
  require_positive("ig: lr", options_.lr);
  require_in_range("ig: rcond", options_.rcond, 0.0, 1.0);
}

Step InverseGradient::step(const Objective& objective, const Vector& x) {
  const Vector dy = y_step(objective, objective.output(x), options_.lr);
  const Vector dx = power_pinv_apply(objective.jacobian(x), dy, {1.0, options_.rcond});
  return {dx, Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
