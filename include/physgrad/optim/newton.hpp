// Newton's method with the exact Hessian: Δx = −η (∂²L/∂x²)⁻¹ ∂L/∂x.
// H = Jᵀ(∂²L/∂y²)J + Σₖ(∂L/∂yₖ)∂²Pₖ/∂x²; a singular H is pseudo-inverted (|λ| ≤ rcond²·|λ|max dropped).
#pragma once

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct NewtonOptions {
  double lr = 1.0;       // η > 0
  // Relative cut on σ = √|λ| of the Hessian solve, in [0, 1) (spectral_cut.hpp): eigenvalues
  // with |λ| ≤ rcond²·|λ|max are dropped (1e-6 on σ is 1e-12 on λ).
  double rcond = 1e-6;

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<NewtonOptions>& descriptors();
};

class Newton final : public Optimizer {
 public:
  using Options = NewtonOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "newton", .label = "Newton", .formula = "Δx = −η H⁻¹ ∂L/∂x, exact Hessian",
         .colour = "#d62728", .derivative = RuleDerivative::kHessian},
    };
    return list;
  }
  explicit Newton(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
};

}  // namespace physgrad
