#include "physgrad/learn/lanczos_hig.hpp"

#include <algorithm>
#include <chrono>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/spectral_cut.hpp"
#include "physgrad/inversion/lanczos.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/timing.hpp"

namespace physgrad {

const OptionList<LanczosHigOptions>& LanczosHigOptions::descriptors() {
  static const OptionList<LanczosHigOptions> options = {
      rule_option("lr", &LanczosHigOptions::lr, positive(), "step size η"),
      kappa_option(&LanczosHigOptions::cut),
      rcond_option(&LanczosHigOptions::cut),
      in_group(OptionGroup::kInversion,
               rule_option("products", &LanczosHigOptions::products, integer_at_least(1),
                           "J Jᵀ products (Lanczos steps) per update of the Krylov rules")),
  };
  return options;
}

LanczosHigUpdate::LanczosHigUpdate(Options options, const std::string& id)
    : options_(options),
      id_(listed_rule_id(rules(), id, rules()[options.cut.kappa == 1.0 ? 0 : 1].id)) {
  check_options(id_, options_);
}

nlohmann::json LanczosHigUpdate::params() const { return option_values(options_); }

void LanczosHigUpdate::set_learning_rate(double lr) {
  Options changed = options_;
  changed.lr = lr;
  options_ = checked(id(), changed);
}

nlohmann::json LanczosHigUpdate::step_info() const {
  if (last_steps_ == 0) return nlohmann::json::object();
  return {{"lanczos_steps", last_steps_}, {"kept_directions", last_kept_}};
}

Step LanczosHigUpdate::step(const BatchState& batch) {
  if (batch.jacobian == nullptr) throw Error(id() + ": the batch has no stacked Jacobian");
  const StackedJacobian& j = *batch.jacobian;
  const Vector& g = batch.loss_gradient_y;
  if (g.size() != j.rows()) {
    throw Error(id() + ": ∂L/∂y has " + std::to_string(g.size()) + " entries, J " +
                std::to_string(j.rows()) + " rows");
  }
  const Index q = std::min<Index>(options_.products, j.rows());
  require_memory(8.0 * static_cast<double>(q) * static_cast<double>(j.cols() + j.rows()),
                 id() + ": " + std::to_string(q) + " Krylov vectors");
  using Clock = std::chrono::steady_clock;
  double product_seconds = 0;
  const auto start = Clock::now();
  // Jᵀ q_j of every Lanczos vector, kept for the final Jᵀ Q c.
  Matrix transposed(j.cols(), q);
  Index made = 0;
  const auto multiply = [&](const Vector& v) {
    const auto begin = Clock::now();
    transposed.col(made) = j.apply_transpose(v);
    Vector out = j.apply(transposed.col(made));
    ++made;
    product_seconds += seconds_since(begin);
    return out;
  };
  // The Ritz values approximate λ = σ² of J Jᵀ: the Gram path's cut, floor included.
  SpectralCut cut = options_.cut;
  cut.floor = std::max(cut.floor, kMinGramRcond);
  Index kept = 0;
  const auto f = [&](const Vector& ritz) {
    CutSpectrum spectrum = cut_squared(cut, ritz);
    kept = spectrum.kept;
    return std::move(spectrum.weights);
  };
  const LanczosApproximation approximation = lanczos_function(multiply, g, q, f);
  Step step;
  step.delta = -options_.lr * (transposed.leftCols(approximation.steps) * approximation.coefficients);
  // Commit the diagnostics only after everything that may throw.
  last_steps_ = approximation.steps;
  last_kept_ = kept;
  step.jacobian_seconds = product_seconds;
  step.inversion_seconds = seconds_since(start) - product_seconds;
  return step;
}

}  // namespace physgrad
