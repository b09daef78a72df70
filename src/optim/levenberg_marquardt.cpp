#include "physgrad/optim/levenberg_marquardt.hpp"

#include <algorithm>
#include <cmath>

namespace physgrad {

LevenbergMarquardt::LevenbergMarquardt(Options options) : options_(options) {
  require_positive("lm: initial_damping", options_.initial_damping);
  require_positive("lm: min_damping", options_.min_damping);
  reset();
}

void LevenbergMarquardt::reset() {
  mu_ = options_.initial_damping;
  nu_ = 2;
}

Step LevenbergMarquardt::step(const Objective& objective, const Vector& x) {
  const Vector y = objective.output(x);
  const double loss = objective.loss().value(y, objective.target());
  const Matrix j = objective.jacobian(x);
  const Matrix a = j.transpose() * objective.loss().hessian(y, objective.target()) * j;
  const Vector g = j.transpose() * objective.loss().gradient(y, objective.target());
  if (g.isZero(0.0)) return {Vector::Zero(x.size()), Step::Status::kOk, {}, 1};

  // Marquardt's scaling by diag(A) keeps the damped step invariant to rescaling each x_i;
  // entries are floored so that directions A does not see are still damped.
  const Vector diag = a.diagonal().cwiseMax(1e-12 * std::max(a.diagonal().maxCoeff(), 1e-300));
  Matrix damped = a;
  damped.diagonal() += mu_ * diag;
  const Vector dx = -damped.ldlt().solve(g);

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
  return {Vector::Zero(x.size()), Step::Status::kRejected, {}, 2};
}

}  // namespace physgrad
