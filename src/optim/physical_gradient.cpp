#include "physgrad/optim/physical_gradient.hpp"

#include "physgrad/inversion/y_step.hpp"

namespace physgrad {

const OptionList<PhysicalGradientOptions>& PhysicalGradientOptions::descriptors() {
  static const OptionList<PhysicalGradientOptions> options = joined<PhysicalGradientOptions>({
      {rule_option("lr", &PhysicalGradientOptions::lr, positive(),
                   "step size η, the fraction of the y-space Newton step")},
      nested_options(&PhysicalGradientOptions::inverse),
  });
  return options;
}

PhysicalGradient::PhysicalGradient(Options options) : options_(checked("pg", options)) {}

nlohmann::json PhysicalGradient::params() const { return option_values(options_); }

Step PhysicalGradient::propose(const Objective& objective, const Vector& x,
                               const Domain& domain) {
  const Vector y = objective.output(x);
  const Vector y_target = y + y_step(objective.loss(), y, objective.target(), options_.lr);
  const LocalInverseResult inverse = local_inverse(objective.simulator(), y_target, x,
                                                   objective.context(), options_.inverse, domain);
  return {inverse.x - x, Step::Status::kOk, {}, 1 + inverse.evaluations};
}

}  // namespace physgrad
