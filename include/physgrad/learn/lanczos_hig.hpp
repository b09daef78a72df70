// LanczosHigUpdate — the κ-family of Jacobian updates made matrix-free: Δθ = −η Jᵀ f(J Jᵀ) ∂L/∂y
// with f(λ) = λ^{−(1+κ)/2} approximated by q Lanczos steps on J Jᵀ (κ = ½ HIG, κ = 1 Gauss-Newton).
#pragma once

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"
#include "physgrad/spectral_cut.hpp"

namespace physgrad {

// Exact HIG is Δθ = −η Jᵀ (J Jᵀ)^{−(1+κ)/2} g over the eigenvalues λ > τ²λ_max of J Jᵀ
// (learn/hig.hpp). This rule never forms J Jᵀ: q Lanczos steps from g (inversion/lanczos.hpp),
// each one product J (Jᵀ v) — a backward pass for Jᵀv and a forward-mode pass of the network
// for J w (StackedJacobian::apply) — give f(J Jᵀ) g ≈ Q c, and Δθ = −η (JᵀQ) c from the Jᵀ
// products already made. f drops the Ritz values θ ≤ τ²θ_max (τ raised to kMinGramRcond, as on
// the Gram path). Cost: q products J Jᵀ v (q backward, q forward-mode passes, no physics call)
// and O(q²·B·m) for the orthogonalization; memory q·(|θ| + B·m) doubles. With q = B·m steps it is
// the exact step up to rounding.
struct LanczosHigOptions {
  double lr = 1.0;      // η > 0
  // κ ½: HIG-like (id "lanczos-hig"), 1: Gauss-Newton (id "lanczos-gn"); the relative
  // truncation τ in [0, 1). No damping; the floor is the Gram path's (kMinGramRcond).
  SpectralCut cut{.kappa = 0.5, .rcond = 1e-6};
  int products = 20;    // q, the J Jᵀ products (Lanczos steps) per update, ≥ 1

  static const OptionList<LanczosHigOptions>& descriptors();
};

class LanczosHigUpdate final : public LearningUpdate {
 public:
  using Options = LanczosHigOptions;
  // Its rules in the catalogue, one per id it is built as, each with its defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "lanczos-gn", .label = "Lanczos GN",
         .formula = "Δθ = −η Jᵀ (J Jᵀ)⁻¹ ∂L/∂y by q Lanczos steps on J Jᵀ, matrix-free",
         .colour = "#c49c94", .defaults = {.cut = LanczosHigOptions{}.cut.with_kappa(1.0)},
         .derivative = RuleDerivative::kJacobianProducts, .settings_from = "gn"},
        {.id = "lanczos-hig", .label = "Lanczos HIG",
         .formula = "Δθ = −η Jᵀ (J Jᵀ)^{−3/4} ∂L/∂y by q Lanczos steps on J Jᵀ, matrix-free",
         .colour = "#2ca25f",
         .derivative = RuleDerivative::kJacobianProducts, .settings_from = "hig"},
    };
    return list;
  }
  // Built as `id`, one of rules(): it reports that id whatever κ is (lanczos-gn with κ = ½
  // is still lanczos-gn); without one, the id of its κ (κ = 1: lanczos-gn, else lanczos-hig). Throws Error
  // naming another id.
  explicit LanczosHigUpdate(Options options = {}, const std::string& id = {});
  std::string id() const override { return id_; }
  nlohmann::json params() const override;
  UpdateNeed need() const override { return UpdateNeed::kStackedJacobian; }
  Step step(const BatchState& batch) override;
  double learning_rate() const override { return options_.lr; }
  void set_learning_rate(double lr) override;
  bool steps_can_be_halved() const override { return true; }
  // The last step's Lanczos steps and kept Ritz values (empty before the first step).
  nlohmann::json step_info() const override;

 private:
  Options options_;
  std::string id_;  // the catalogue id it was built as
  Index last_steps_ = 0, last_kept_ = 0;
};

}  // namespace physgrad
