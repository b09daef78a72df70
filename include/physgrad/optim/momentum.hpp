// Gradient descent with heavy-ball momentum: v ← β v + ∂L/∂x, Δx = −η v.
// With β = 0 it is plain gradient descent.
#pragma once

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct MomentumOptions {
  double lr = 0.01;   // η > 0
  double beta = 0.9;  // 0 ≤ β < 1

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<MomentumOptions>& descriptors();
};

class Momentum final : public Optimizer {
 public:
  using Options = MomentumOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "momentum", .label = "Momentum", .formula = "v ← βv + ∂L/∂x, Δx = −η v",
         .colour = "#17becf"},
    };
    return list;
  }
  explicit Momentum(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }
  void reset() override { velocity_.resize(0); }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
  Vector velocity_;
};

}  // namespace physgrad
