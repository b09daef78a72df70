#include "physgrad/optim/inverse_gradient.hpp"

#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/inversion/y_step.hpp"
#include "physgrad/spectral_cut.hpp"

namespace physgrad {

const OptionList<InverseGradientOptions>& InverseGradientOptions::descriptors() {
  static const OptionList<InverseGradientOptions> options = {
      rule_option("lr", &InverseGradientOptions::lr, positive(),
                  "step size η, the fraction of the y-space Newton step"),
      rcond_option(&InverseGradientOptions::rcond),
  };
  return options;
}

InverseGradient::InverseGradient(Options options) : options_(checked("ig", options)) {}

Step InverseGradient::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  const Vector y = objective.output(x);
  const Vector dy = y_step(objective.loss(), y, objective.target(), options_.lr);
  const Matrix j = objective.jacobian(x);
  // Held variables (Domain::free_variables, by the gradient Jᵀ ∂L/∂y) keep their value; the
  // others move by Δz_F = (J[:, F] D_F)⁺ Δy, Δx_F = D_F Δz_F.
  const Vector gradient = domain.bounded()
                              ? Vector(j.transpose() * objective.loss().gradient(y, objective.target()))
                              : Vector::Zero(x.size());
  const FreeSubspace free(domain, x, gradient);
  const Vector dz =
      power_pinv_apply(free.columns(j), dy, {.cut = {.kappa = 1.0, .rcond = options_.rcond}});
  return {free.step(dz), Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
