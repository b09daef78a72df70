#include "physgrad/optim/learning_update.hpp"

#include <chrono>

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
  const auto start = std::chrono::steady_clock::now();
  Vector direction = power_pinv_apply(batch.jacobian, batch.loss_gradient_y, pinv_, &info_);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {-lr_ * direction, seconds};
}

const std::vector<std::string>& learning_update_ids() {
  static const std::vector<std::string> ids = {"sgd", "adam", "gn", "hig"};
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
