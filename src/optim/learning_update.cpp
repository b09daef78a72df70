#include "physgrad/optim/learning_update.hpp"

#include <chrono>
#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

SgdUpdate::SgdUpdate(double lr) : lr_(lr) { require_positive("sgd: lr", lr); }

UpdateStep SgdUpdate::step(const BatchState& batch) { return {-lr_ * batch.gradient, 0}; }

AdamUpdate::AdamUpdate(AdamOptions options) : state_(options) {}

nlohmann::json AdamUpdate::params() const {
  const AdamOptions& o = state_.options();
  return {{"lr", o.lr}, {"beta1", o.beta1}, {"beta2", o.beta2}, {"epsilon", o.epsilon}};
}

JacobianInverseUpdate::JacobianInverseUpdate(std::string id, double lr, PowerPinvOptions pinv)
    : id_(std::move(id)), lr_(lr), pinv_(pinv) {
  require_positive((id_ + ": lr").c_str(), lr);
  require_in_range((id_ + ": rcond").c_str(), pinv.rcond, 0.0, 1.0);
}

nlohmann::json JacobianInverseUpdate::params() const {
  return {{"lr", lr_}, {"kappa", pinv_.kappa}, {"rcond", pinv_.rcond},
          {"backend", to_string(pinv_.backend)}};
}

UpdateStep JacobianInverseUpdate::step(const BatchState& batch) {
  if (batch.jacobian == nullptr) throw Error(id_ + ": the batch has no stacked Jacobian");
  using Clock = std::chrono::steady_clock;
  const StackedJacobian& j = *batch.jacobian;
  const bool factored = resolve_pinv_backend(j.rows(), j.cols(), pinv_) == PinvBackend::kGram;
  UpdateStep step;
  const auto start = Clock::now();
  Matrix formed = factored ? j.gram() : j.materialize();
  const auto formed_at = Clock::now();
  step.jacobian_seconds = std::chrono::duration<double>(formed_at - start).count();
  if (!all_finite(formed)) {
    step.delta = Vector::Constant(j.cols(), NAN);
    return step;
  }
  const Vector direction =
      factored ? power_pinv_apply_gram(std::move(formed), batch.loss_gradient_y,
                                       [&j](const Vector& c) { return j.apply_transpose(c); },
                                       pinv_, &info_)
               : power_pinv_apply(formed, batch.loss_gradient_y, pinv_, &info_);
  step.inversion_seconds = std::chrono::duration<double>(Clock::now() - formed_at).count();
  step.delta = -lr_ * direction;
  return step;
}

SipUpdate::SipUpdate(SipOptions options) : options_(options), adam_(options.adam) {
  require_positive("sip: y_step", options.y_step);
}

nlohmann::json SipUpdate::params() const {
  return {{"lr", options_.adam.lr},
          {"y_step", options_.y_step},
          {"inverse", to_string(options_.inverse.method)}};
}

UpdateStep SipUpdate::step(const BatchState& batch) {
  if (batch.physics == nullptr || batch.loss_function == nullptr || !batch.backprop) {
    throw Error("sip: the batch lacks the network outputs and backprop it needs");
  }
  const auto start = std::chrono::steady_clock::now();
  const Index count = batch.x.cols();
  Matrix cotangent(batch.x.rows(), count);
  for (Index i = 0; i < count; ++i) {
    const Vector y = batch.y.col(i), target = batch.targets.col(i), x = batch.x.col(i);
    const Vector context = batch.context.size() == 0 ? Vector() : Vector(batch.context.col(i));
    const Vector y_target = y + options_.y_step * batch.loss_function->newton_step(y, target);
    const Vector x_tilde =
        local_inverse(*batch.physics, y_target, x, context, options_.inverse).x;
    // The mean is over the whole mini-batch, which in a data-parallel run (batch_size) spans
    // more samples than this process's columns.
    const Index divisor = batch.batch_size > count ? batch.batch_size : count;
    cotangent.col(i) = (x - x_tilde) / static_cast<double>(divisor);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {adam_.update(batch.backprop(cotangent)), seconds};
}

const std::vector<std::string>& learning_update_ids() {
  static const std::vector<std::string> ids = {"sgd", "adam", "gn", "hig", "sip"};
  return ids;
}

std::unique_ptr<LearningUpdate> make_learning_update(const std::string& id,
                                                     const LearningUpdateSettings& settings) {
  const double rcond = settings.rcond.value_or(1e-6);
  if (id == "sgd") return std::make_unique<SgdUpdate>(settings.lr.value_or(1e-2));
  if (id == "adam") {
    AdamOptions options;
    options.lr = settings.lr.value_or(1e-3);
    return std::make_unique<AdamUpdate>(options);
  }
  if (id == "sip") {
    SipOptions options;
    options.adam.lr = settings.lr.value_or(1e-3);
    options.y_step = settings.sip_y_step;
    options.inverse.method = settings.inverse;
    return std::make_unique<SipUpdate>(options);
  }
  if (id == "gn" || id == "hig") {
    const double kappa = id == "gn" ? 1.0 : 0.5;
    return std::make_unique<JacobianInverseUpdate>(id, settings.lr.value_or(1.0),
                                                   PowerPinvOptions{kappa, rcond, settings.backend});
  }
  std::string known;
  for (const std::string& name : learning_update_ids()) known += (known.empty() ? "" : ", ") + name;
  throw Error("unknown learning update '" + id + "' (known: " + known + ")");
}

}  // namespace physgrad
