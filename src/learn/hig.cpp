#include "physgrad/learn/hig.hpp"

#include "physgrad/error.hpp"

namespace physgrad {

const OptionList<HigOptions>& HigOptions::descriptors() {
  static const OptionList<HigOptions> options = {
      rule_option("lr", &HigOptions::lr, positive(), "step size η"),
      rule_option("kappa", &HigOptions::kappa, any_finite(),
                  "exponent κ of J^{−κ}: ½ HIG, 1 Gauss-Newton"),
      rule_option("rcond", &HigOptions::rcond, fraction(),
                  "relative truncation τ: singular values σ ≤ τσ_max of J are dropped"),
      rule_option("backend", &HigOptions::backend,
                  {PinvBackend::kAuto, PinvBackend::kSvd, PinvBackend::kGram, PinvBackend::kNormal},
                  "how J^{−κ} is computed (inversion/power_pinv.hpp)"),
  };
  return options;
}

HigUpdate::HigUpdate(Options options) : options_(options) { check_options(id(), options_); }

nlohmann::json HigUpdate::params() const { return option_values(options_); }

void HigUpdate::set_learning_rate(double lr) {
  Options changed = options_;
  changed.lr = lr;
  options_ = checked(id(), changed);
}

Step HigUpdate::step(const BatchState& batch) {
  if (batch.jacobian == nullptr) throw Error(id() + ": the batch has no stacked Jacobian");
  PowerPinvTiming timing;
  Step step;
  step.delta = -options_.lr * power_pinv_apply(*batch.jacobian, batch.loss_gradient_y,
                                               {options_.kappa, options_.rcond, options_.backend},
                                               &info_, &timing);
  step.jacobian_seconds = timing.forming_seconds;
  step.inversion_seconds = timing.inversion_seconds;
  return step;
}

}  // namespace physgrad
