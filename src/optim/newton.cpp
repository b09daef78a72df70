#include "physgrad/optim/newton.hpp"

#include "physgrad/linalg/power_pinv.hpp"

namespace physgrad {

Newton::Newton(Options options) : options_(options) {
  require_positive("newton: lr", options_.lr);
  require_in_range("newton: rcond", options_.rcond, 0.0, 1.0);
}

Step Newton::step(const Objective& objective, const Vector& x) {
  const Vector g = objective.gradient(x);
  const Vector dx = -options_.lr * symmetric_pinv_apply(objective.hessian(x), g, options_.rcond);
  return {dx, Step::Status::kOk, {}, 2};
}

}  // namespace physgrad
