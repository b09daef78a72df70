#include "physgrad/learn/hig.hpp"

#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"
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
          {"backend", to_string(options_.backend)},
          {"precision", to_string(options_.precision)},
          {"eigensolver", to_string(options_.eigensolver)}};
}

nlohmann::json HigUpdate::state() const {
  if (info_.backend == PinvBackend::kAuto) return nullptr;
  return {{"backend", to_string(info_.backend)},
          {"rank", info_.rank},
          {"sigma_max", info_.sigma_max},
          {"sigma_min_kept", info_.sigma_min_kept},
          {"rcond_used", info_.rcond_used},
          {"precision", to_string(info_.precision)},
          {"eigensolver", to_string(info_.eigensolver)},
          {"float_rejected", info_.float_rejected},
          {"float_resolves", info_.float_resolves}};
}

void HigUpdate::restore(const nlohmann::json& state, Index /*parameter_count*/) {
  info_ = {};
  if (state.is_null()) return;
  const auto flag = [&state](const char* key) {
    if (!state.contains(key) || !state.at(key).is_boolean()) {
      throw Error(std::string("checkpoint field '") + key + "': expected true or false");
    }
    return state.at(key).get<bool>();
  };
  PowerPinvInfo info;
  info.backend = parse_pinv_backend(string_from_json(state, "backend"));
  info.rank = static_cast<Index>(integer_from_json(state, "rank"));
  info.sigma_max = real_from_json(state, "sigma_max");
  info.sigma_min_kept = real_from_json(state, "sigma_min_kept");
  info.rcond_used = real_from_json(state, "rcond_used");
  info.precision = parse_pinv_precision(string_from_json(state, "precision"));
  info.eigensolver = parse_pinv_eigensolver(string_from_json(state, "eigensolver"));
  info.float_rejected = flag("float_rejected");
  info.float_resolves = flag("float_resolves");
  info_ = info;
}

nlohmann::json HigUpdate::step_info() const {
  if (info_.backend == PinvBackend::kAuto) return nlohmann::json::object();  // no step yet
  return {{"pinv_path", to_string(info_.backend)},
          {"pinv_precision", to_string(info_.precision)},
          {"pinv_eigensolver", to_string(info_.eigensolver)},
          {"kept_directions", info_.rank},
          {"kept_condition", kept_condition(info_)}};
}

void HigUpdate::set_learning_rate(double lr) {
  require_positive((id() + ": lr").c_str(), lr);
  options_.lr = lr;
}

Step HigUpdate::step(const BatchState& batch) {
  if (batch.jacobian == nullptr) throw Error(id() + ": the batch has no stacked Jacobian");
  PowerPinvTiming timing;
  // The previous step's spectrum guides the auto choices when it came from the same path.
  const PowerPinvInfo previous = info_;
  const bool same_path =
      previous.backend == resolve_pinv_backend(batch.jacobian->rows(), batch.jacobian->cols(),
                                               {.rcond = options_.rcond, .backend = options_.backend});
  Step step;
  step.delta = -options_.lr * power_pinv_apply(*batch.jacobian, batch.loss_gradient_y,
                                               {.kappa = options_.kappa,
                                                .rcond = options_.rcond,
                                                .backend = options_.backend,
                                                .precision = options_.precision,
                                                .eigensolver = options_.eigensolver,
                                                .previous = same_path ? &previous : nullptr},
                                               &info_, &timing);
  step.jacobian_seconds = timing.forming_seconds;
  step.inversion_seconds = timing.inversion_seconds;
  return step;
}

}  // namespace physgrad
