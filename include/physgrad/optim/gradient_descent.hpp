// Gradient descent: Δx = −η ∂L/∂x.
// The baseline every inverted update is compared against; its steps scale with the square of
// the problem's sensitivity.
#pragma once

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct GradientDescentOptions {
  double lr = 0.01;  // η > 0

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<GradientDescentOptions>& descriptors();
};

class GradientDescent final : public Optimizer {
 public:
  using Options = GradientDescentOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "gd", .label = "GD", .formula = "Δx = −η ∂L/∂x", .colour = "#1f77b4"},
    };
    return list;
  }
  explicit GradientDescent(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  Options options_;
};

}  // namespace physgrad
