#include "physgrad/optim/newton.hpp"

#include "physgrad/inversion/power_pinv.hpp"

namespace physgrad {

Newton::Newton(Options options) : options_(options) {
  require_positive("newton: lr", options_.lr);
  require_in_range("newton: rcond", options_.rcond, 0.0, 1.0);
}

Step Newton::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  // In the free variables z_F: Δz_F = −η (D_F H_FF D_F)⁺ D_F g_F, held variables stay.
  const Vector g = objective.gradient(x);
  const FreeSubspace free(domain, x, g);
  const Vector dz = -options_.lr * symmetric_pinv_apply(free.square(objective.hessian(x)),
                                                        free.covector(g), options_.rcond);
  return {free.step(dz), Step::Status::kOk, {}, 2};
}

}  // namespace physgrad
