#include "physgrad/learn/hig.hpp"

#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

HigUpdate::HigUpdate(Options options) : options_(options) {
  require_positive((id() + ": lr").c_str(), options_.lr);
  require_in_range((id() + ": rcond").c_str(), options_.rcond, 0.0, 1.0);
  if (!std::isfinite(options_.kappa)) throw Error(id() + ": kappa must be finite");
}

nlohmann::json HigUpdate::params() const {
  return {{"lr", options_.lr},
          {"kappa", options_.kappa},
          {"rcond", options_.rcond},
          {"backend", to_string(options_.backend)}};
}

void HigUpdate::set_learning_rate(double lr) {
  require_positive((id() + ": lr").c_str(), lr);
  options_.lr = lr;
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
