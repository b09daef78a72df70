// Physical gradient (PG), the update through an inverse simulator: Δx = P⁻¹(y₀ + Δy; x₀) − x₀
// with y₀ = P(x₀), Δy = η·(Newton step of L in y), and P⁻¹(·; x₀) a local inverse.
#pragma once

#include "physgrad/optim/local_inverse.hpp"
#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct PhysicalGradientOptions {
  double lr = 1.0;  // η > 0
  // kAnalytic needs a simulator with has_inverse(), kTimeReversal one with has_time_reversal();
  // the numerical methods work for any simulator with a VJP.
  LocalInverseOptions inverse{};

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<PhysicalGradientOptions>& descriptors();
};

// Bounds and x_scale go to the local inverse: the numerical inverses solve inside the box in the
// scaled variables, the analytic and time-reversal results are projected onto it.

class PhysicalGradient final : public Optimizer {
 public:
  using Options = PhysicalGradientOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "pg", .label = "PG", .formula = "Δx = P⁻¹(y + Δy; x) − x, Δy = η (y* − y)",
         .colour = "#bcbd22"},
    };
    return list;
  }
  explicit PhysicalGradient(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override;

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
};

}  // namespace physgrad
