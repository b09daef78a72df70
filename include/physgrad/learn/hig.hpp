// HigUpdate — the κ-family of Jacobian updates: Δθ = −η J^{−κ} ∂(mean L)/∂y with the truncated
// power-pseudo-inverse of the stacked Jacobian; κ = ½ half-inverse gradients, κ = 1 Gauss-Newton.
#pragma once

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

// J = U Σ Vᵀ, J^{−κ} = V Σ^{−κ} Uᵀ over σᵢ > rcond·σ_max (the others contribute nothing), as in
// the HIG paper's code (docs/reference_experiments.md). The path (Gram, normal, SVD) follows J's
// shape (inversion/power_pinv.hpp); on the Gram path J Jᵀ comes from the network's layer factors.
struct HigOptions {
  double lr = 1.0;  // η > 0
  // κ ½: HIG, 1: Gauss-Newton (id "gn"); the relative truncation τ in [0, 1). Without damping;
  // the path sets the floor (inversion/power_pinv.hpp). A braced {.rcond = …} starts from
  // SpectralCut's own defaults (κ = 1); `options.cut.rcond = …` changes the rule's default cut.
  SpectralCut cut{.kappa = 0.5, .rcond = 1e-6};
  PinvBackend backend = PinvBackend::kAuto;
  // The eigensolve of the Gram and normal paths (inversion/power_pinv.hpp); each step's auto
  // choice follows the previous step's spectrum. Double by default: float changes a step by up to
  // ~1e-3 relative, which the bit-level agreement of data-parallel runs does not allow.
  PinvPrecision precision = PinvPrecision::kDouble;
  PinvEigensolver eigensolver = PinvEigensolver::kAuto;

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<HigOptions>& descriptors();
};

class HigUpdate final : public LearningUpdate {
 public:
  using Options = HigOptions;
  // Its rules in the catalogue, one per id it is built as, each with its defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "gn", .label = "Gauss-Newton",
         .formula = "Δθ = −η J⁺ ∂L/∂y, J the stacked Jacobian, σ ≤ τσ_max dropped",
         .colour = "#8c564b", .defaults = {.cut = HigOptions{}.cut.with_kappa(1.0)},
         .derivative = RuleDerivative::kJacobian,
         .pretrained_colour = "#c51b7d"},
        {.id = "hig", .label = "HIG",
         .formula = "Δθ = −η V Σ^{−1/2} Uᵀ ∂L/∂y, J = UΣVᵀ, σ ≤ τσ_max dropped",
         .colour = "#00633a", .derivative = RuleDerivative::kJacobian,
         .pretrained_colour = "#7b3294"},
    };
    return list;
  }
  // Built as `id`, one of rules(): it reports that id whatever κ is (gn with κ = ½ is still
  // gn); without one, the id of its κ (κ = 1: gn, else hig). Throws Error naming another id.
  explicit HigUpdate(Options options = {}, const std::string& id = {});
  std::string id() const override { return id_; }
  nlohmann::json params() const override;
  UpdateNeed need() const override { return UpdateNeed::kStackedJacobian; }
  Step step(const BatchState& batch) override;
  double learning_rate() const override { return options_.lr; }
  void set_learning_rate(double lr) override;
  bool steps_can_be_halved() const override { return true; }
  // The last step's inversion info (the auto choices of the next step follow it; null before
  // the first step), so that a resumed run chooses as an uninterrupted one.
  void reset() override { info_ = {}; }
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state, Index parameter_count) override;
  // What the last step's inversion did: path, kept rank, σ_max/σ_min,kept, precision, eigensolver.
  const PowerPinvInfo& last_info() const { return info_; }
  nlohmann::json step_info() const override;

 private:
  Options options_;
  std::string id_;  // the catalogue id it was built as
  PowerPinvInfo info_{};
};

}  // namespace physgrad
