#include "physgrad/optim/physical_gradient.hpp"

#include "physgrad/optim/inverse_gradient.hpp"

namespace physgrad {

PhysicalGradient::PhysicalGradient(Options options) : options_(options) {
  require_positive("pg: lr", options_.lr);
}

nlohmann::json PhysicalGradient::params() const {
  nlohmann::json params = {{"lr", options_.lr}, {"inverse", to_string(options_.inverse.method)}};
  if (options_.inverse.method != InverseMethod::kAnalytic) {
    params["inverse_tolerance"] = options_.inverse.tolerance;
    params["inverse_iterations"] = options_.inverse.max_iterations;
  }
  return params;
}

Step PhysicalGradient::step(const Objective& objective, const Vector& x) {
  const Vector y = objective.output(x);
  const Vector y_target = y + y_step(objective, y, options_.lr);
  const LocalInverseResult inverse =
      local_inverse(objective.simulator(), y_target, x, objective.context(), options_.inverse);
  return {inverse.x - x, Step::Status::kOk, {}, 1 + inverse.iterations};
}

}  // namespace physgrad
