// Gauss-Newton: Δx = −η (Jᵀ H_y J)⁺ Jᵀ ∂L/∂y with J = ∂P/∂x and H_y = ∂²L/∂y².
// For an L2 loss (H_y = w·I) this is −η J⁺ (y − y*): the inverse-gradient step with Δy = η(y* − y).
#pragma once

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct GaussNewtonOptions {
  double lr = 1.0;       // η > 0
  // Relative cut on σ, in [0, 1) (spectral_cut.hpp): the eigenvalues λ = σ² of Jᵀ H_y J with
  // λ ≤ rcond²·λ_max are dropped (1e-6 on σ is 1e-12 on λ).
  double rcond = 1e-6;

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<GaussNewtonOptions>& descriptors();
};

class GaussNewton final : public Optimizer {
 public:
  using Options = GaussNewtonOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "gn", .label = "Gauss-Newton", .formula = "Δx = −η (JᵀH_yJ)⁺ Jᵀ ∂L/∂y",
         .colour = "#8c564b", .derivative = RuleDerivative::kJacobian},
    };
    return list;
  }
  explicit GaussNewton(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
};

}  // namespace physgrad
