#include "physgrad/optim/physical_gradient.hpp"

#include "physgrad/inversion/y_step.hpp"

namespace physgrad {

PhysicalGradient::PhysicalGradient(Options options) : options_(options) {
  require_positive("pg: lr", options_.lr);
}

nlohmann::json PhysicalGradient::params() const {
  nlohmann::json params = local_inverse_params(options_.inverse);
  params["lr"] = options_.lr;
  return params;
}

Step PhysicalGradient::propose(const Objective& objective, const Vector& x,
                               const Domain& domain) {
  const Vector y = objective.output(x);
  const Vector y_target = y + y_step(objective.loss(), y, objective.target(), options_.lr);
  const LocalInverseResult inverse = local_inverse(objective.simulator(), y_target, x,
                                                   objective.context(), options_.inverse, domain);
  return {inverse.x - x, Step::Status::kOk, {}, 1 + inverse.evaluations};
}

}  // namespace physgrad
