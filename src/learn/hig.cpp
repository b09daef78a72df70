#include "physgrad/learn/hig.hpp"

#include "physgrad/error.hpp"
#include "physgrad/spectral_cut.hpp"
#include "physgrad/io/serialize.hpp"

namespace physgrad {

const OptionList<HigOptions>& HigOptions::descriptors() {
  static const OptionList<HigOptions> options = {
      rule_option("lr", &HigOptions::lr, positive(), "step size η"),
      kappa_option(&HigOptions::cut),
      rcond_option(&HigOptions::cut),
      rule_option("backend", &HigOptions::backend,
                  {PinvBackend::kAuto, PinvBackend::kSvd, PinvBackend::kGram, PinvBackend::kNormal},
                  "how J^{−κ} is computed (inversion/power_pinv.hpp)"),
      in_group(OptionGroup::kInversion, rule_option("precision", &HigOptions::precision,
                  {PinvPrecision::kDouble, PinvPrecision::kFloat, PinvPrecision::kAuto},
                  "precision of the eigendecomposition (auto: float where the last spectrum "
                  "allows it)")),
      in_group(OptionGroup::kInversion, rule_option("eigensolver", &HigOptions::eigensolver,
                  {PinvEigensolver::kAuto, PinvEigensolver::kTridiagonal, PinvEigensolver::kFull,
                   PinvEigensolver::kSubset},
                  "eigenvalues with rotations applied to the one vector (tridiagonal), all "
                  "eigenpairs (full) or only the kept ones (subset); auto by the last step")),
  };
  return options;
}

HigUpdate::HigUpdate(Options options, const std::string& id)
    : options_(options),
      id_(listed_rule_id(rules(), id, rules()[options.cut.kappa == 1.0 ? 0 : 1].id)) {
  check_options(id_, options_);
}

nlohmann::json HigUpdate::params() const { return option_values(options_); }

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
  Options changed = options_;
  changed.lr = lr;
  options_ = checked(id(), changed);
}

Step HigUpdate::step(const BatchState& batch) {
  if (batch.jacobian == nullptr) throw Error(id() + ": the batch has no stacked Jacobian");
  PowerPinvTiming timing;
  // The previous step's spectrum guides the auto choices when it came from the same path.
  const PowerPinvInfo previous = info_;
  PowerPinvOptions pinv{.cut = options_.cut,
                        .backend = options_.backend,
                        .precision = options_.precision,
                        .eigensolver = options_.eigensolver};
  if (previous.backend ==
      resolve_pinv_backend(batch.jacobian->rows(), batch.jacobian->cols(), pinv)) {
    pinv.previous = &previous;
  }
  Step step;
  step.delta =
      -options_.lr * power_pinv_apply(*batch.jacobian, batch.loss_gradient_y, pinv, &info_, &timing);
  step.jacobian_seconds = timing.forming_seconds;
  step.inversion_seconds = timing.inversion_seconds;
  return step;
}

}  // namespace physgrad
