#include "physgrad/optim/gauss_newton.hpp"

#include "physgrad/inversion/power_pinv.hpp"

namespace physgrad {

GaussNewton::GaussNewton(Options options) : options_(options) {
  require_positive("gn: lr", options_.lr);
  require_in_range("gn: rcond", options_.rcond, 0.0, 1.0);
}

Step GaussNewton::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  const Vector y = objective.output(x);
  const Matrix j = objective.jacobian(x);
  const Matrix curvature = j.transpose() * objective.loss().hessian(y, objective.target()) * j;
  const Vector gradient = j.transpose() * objective.loss().gradient(y, objective.target());
  // In the free variables z_F (the transformed variable): J_z = J[:, F] D_F.
  const FreeSubspace free(domain, x, gradient);
  const Vector dz = -options_.lr * symmetric_pinv_apply(free.square(curvature),
                                                        free.covector(gradient), options_.rcond);
  return {free.step(dz), Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
