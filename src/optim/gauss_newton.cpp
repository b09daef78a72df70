#include "physgrad/optim/gauss_newton.hpp"

#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/spectral_cut.hpp"

namespace physgrad {

const OptionList<GaussNewtonOptions>& GaussNewtonOptions::descriptors() {
  static const OptionList<GaussNewtonOptions> options = {
      rule_option("lr", &GaussNewtonOptions::lr, positive(), "step size η"),
      rcond_option(&GaussNewtonOptions::rcond),
  };
  return options;
}

GaussNewton::GaussNewton(Options options) : options_(checked("gn", options)) {}

Step GaussNewton::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  const Vector y = objective.output(x);
  const Matrix j = objective.jacobian(x);
  const Matrix curvature = j.transpose() * objective.loss().hessian(y, objective.target()) * j;
  const Vector gradient = j.transpose() * objective.loss().gradient(y, objective.target());
  // In the free variables z_F (the transformed variable): J_z = J[:, F] D_F.
  const FreeSubspace free(domain, x, gradient);
  const Vector dz = -options_.lr * symmetric_pinv_apply(free.square(curvature),
                                                        free.covector(gradient),
                                                        {.rcond = options_.rcond});
  return {free.step(dz), Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
