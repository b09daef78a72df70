#include "physgrad/learn/sip.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/inversion/y_step.hpp"
#include "physgrad/optim/optimizer.hpp"
#include "physgrad/timing.hpp"

namespace physgrad {

const OptionList<SipOptions>& SipOptions::descriptors() {
  static const OptionList<SipOptions> options = joined<SipOptions>({
      nested_options(&SipOptions::adam),
      {rule_option("y_step", &SipOptions::y_step, positive(),
                   "fraction η of the Newton step in y")},
      nested_options(&SipOptions::inverse),
  });
  return options;
}

SipUpdate::SipUpdate(Options options) : options_(checked("sip", options)), adam_(options.adam) {}

nlohmann::json SipUpdate::params() const { return option_values(options_); }

void SipUpdate::set_learning_rate(double lr) {
  Options changed = options_;
  changed.adam.lr = lr;
  options_ = checked("sip", changed);
  adam_.set_learning_rate(lr);
}

Step SipUpdate::step(const BatchState& batch) {
  if (batch.physics == nullptr || batch.loss_function == nullptr || !batch.backprop) {
    throw Error("sip: the batch lacks the network outputs and backprop it needs");
  }
  const auto start = std::chrono::steady_clock::now();
  const Index count = batch.x.cols();
  // The mean is over the whole mini-batch, which in a data-parallel run (batch_size) spans
  // more samples than this process's columns.
  const auto divisor = static_cast<double>(std::max(batch.batch_size, count));
  Step step;
  Matrix cotangent(batch.x.rows(), count);
  for (Index i = 0; i < count; ++i) {
    const Vector y = batch.y.col(i), target = batch.targets.col(i), x = batch.x.col(i);
    const Vector context = batch.context.size() == 0 ? Vector() : Vector(batch.context.col(i));
    const Vector y_target = y + y_step(*batch.loss_function, y, target, options_.y_step);
    Vector x_tilde;
    try {
      x_tilde = local_inverse(*batch.physics, y_target, x, context, options_.inverse).x;
    } catch (const NumericalError& e) {
      x_tilde = Vector::Constant(x.size(), NAN);
      if (step.message.empty()) step.message = e.what();
    }
    if (!all_finite(x_tilde) && step.message.empty()) {
      step.message = "the local inverse (" + to_string(options_.inverse.method) +
                     ") gave no finite preimage";
    }
    cotangent.col(i) = (x - x_tilde) / divisor;
  }
  step.inversion_seconds = seconds_since(start);
  // Every rank takes part in backprop's sum, also with a NaN cotangent, so no rank waits alone;
  // a non-finite proxy gradient leaves Adam's moments as they were.
  const Vector gradient = batch.backprop(cotangent);
  if (!all_finite(gradient)) {
    step.delta = Vector::Constant(gradient.size(), NAN);
    if (step.message.empty()) step.message = "the proxy gradient is not finite";
    return step;
  }
  step.delta = adam_.update(gradient);
  return step;
}

}  // namespace physgrad
