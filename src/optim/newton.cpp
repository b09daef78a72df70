#include "physgrad/optim/newton.hpp"

#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/spectral_cut.hpp"

namespace physgrad {

const OptionList<NewtonOptions>& NewtonOptions::descriptors() {
  static const OptionList<NewtonOptions> options = {
      rule_option("lr", &NewtonOptions::lr, positive(), "step size η"),
      rcond_option(&NewtonOptions::rcond),
  };
  return options;
}

Newton::Newton(Options options) : options_(checked("newton", options)) {}

Step Newton::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  // In the free variables z_F: Δz_F = −η (D_F H_FF D_F)⁺ D_F g_F, held variables stay.
  const Vector g = objective.gradient(x);
  const FreeSubspace free(domain, x, g);
  const Vector dz = -options_.lr * symmetric_pinv_apply(free.square(objective.hessian(x)),
                                                        free.covector(g),
                                                        {.rcond = options_.rcond});
  return {free.step(dz), Step::Status::kOk, {}, 2};
}

}  // namespace physgrad
