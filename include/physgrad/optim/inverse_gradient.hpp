// Inverse gradient (IG): Δx = J⁺ Δy with J = ∂P/∂x and Δy = η·(Newton step of L in y)
// (inversion/y_step.hpp); J⁺ is the truncated pseudo-inverse (inversion/power_pinv.hpp, κ = 1).
#pragma once

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct InverseGradientOptions {
  double lr = 1.0;       // η > 0, the fraction of the y-space Newton step
  double rcond = 1e-10;  // truncation of J's singular values, in [0, 1)

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<InverseGradientOptions>& descriptors();
};

class InverseGradient final : public Optimizer {
 public:
  using Options = InverseGradientOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "ig", .label = "IG", .formula = "Δx = J⁺ Δy, Δy = η (y* − y)", .colour = "#2ca02c",
         .derivative = RuleDerivative::kJacobian},
    };
    return list;
  }
  explicit InverseGradient(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
};

}  // namespace physgrad
