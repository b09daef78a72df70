#include "physgrad/optim/levenberg_marquardt.hpp"

#include <algorithm>
#include <cmath>

#include "physgrad/error.hpp"

namespace physgrad {

const OptionList<LevenbergMarquardtOptions>& LevenbergMarquardtOptions::descriptors() {
  static const OptionList<LevenbergMarquardtOptions> options = {
      rule_option("initial_damping", &LevenbergMarquardtOptions::initial_damping, positive(),
                  "damping μ₀ of the first step, relative to diag(A)"),
      rule_option("min_damping", &LevenbergMarquardtOptions::min_damping, positive(),
                  "μ never drops below this"),
  };
  return options;
}

LevenbergMarquardt::LevenbergMarquardt(Options options) : options_(checked("lm", options)) {
  reset();
}

void LevenbergMarquardt::reset() {
  mu_ = options_.initial_damping;
  nu_ = 2;
  unit_ = 0;
}

Step LevenbergMarquardt::propose(const Objective& objective, const Vector& x,
                                 const Domain& domain) {
  const Vector y = objective.output(x);
  const double loss = objective.loss().value(y, objective.target());
  const Matrix j = objective.jacobian(x);
  // Damping cannot cure a non-finite model at x: every trial would be rejected until μ
  // overflows, and the cause would go unnamed.
  if (!std::isfinite(loss)) throw NumericalError("the loss at x is not finite");
  if (!all_finite(j)) throw NumericalError("the Jacobian at x has non-finite entries");
  const Matrix a = j.transpose() * objective.loss().hessian(y, objective.target()) * j;
  const Vector g = j.transpose() * objective.loss().gradient(y, objective.target());
  if (!all_finite(a) || !all_finite(g)) {
    throw NumericalError("JᵀH_yJ or the gradient Jᵀ∂L/∂y at x is not finite");
  }
  const FreeSubspace free(domain, x, g);
  const Vector gz = free.covector(g);
  if (gz.isZero(0.0)) return {Vector::Zero(x.size()), Step::Status::kOk, {}, 1};

  // The damped system in the free scaled variables z_F. Without x_scale: Marquardt's scaling by
  // diag(A_z), which keeps the step invariant to rescaling each x_i (entries floored so that
  // directions A does not see are still damped). With x_scale: the identity in z, i.e. a trust
  // region on ‖Δx ⊘ s‖ (MINPACK's diag = 1/x_scale), in units of the largest diag(A_z) of the
  // first step.
  const Matrix az = free.square(a);
  Vector diag;
  if (domain.scaled()) {
    if (unit_ == 0) unit_ = std::max(az.diagonal().maxCoeff(), 1e-300);
    diag = Vector::Constant(az.rows(), unit_);
  } else {
    diag = az.diagonal().cwiseMax(1e-12 * std::max(az.diagonal().maxCoeff(), 1e-300));
  }
  Matrix damped = az;
  damped.diagonal() += mu_ * diag;
  const Vector dx = free.step(-damped.ldlt().solve(gz));

  // The gain ratio of the step actually taken (cut to the box), against the model in x.
  const double predicted = -(g.dot(dx) + 0.5 * dx.dot(a * dx));
  const double trial = objective.value(x + dx);
  const double rho = (loss - trial) / predicted;
  if (std::isfinite(trial) && std::isfinite(rho) && predicted > 0 && rho > 0) {
    mu_ = std::max(options_.min_damping, mu_ * std::max(1.0 / 3.0, 1 - std::pow(2 * rho - 1, 3)));
    nu_ = 2;
    return {dx, Step::Status::kOk, {}, 2};
  }
  mu_ *= nu_;
  nu_ *= 2;
  if (!std::isfinite(mu_)) {
    return {Vector::Zero(x.size()), Step::Status::kFailed, "lm: damping overflowed; no descent found", 2};
  }
  // A trial whose loss is not finite is too long, not short: its length is not tested.
  return {std::isfinite(trial) ? dx : Vector(), Step::Status::kRejected, {}, 2};
}

}  // namespace physgrad
