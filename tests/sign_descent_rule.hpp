// Sign descent — a direct rule that lives outside the library: Δx = −η s ⊙ sign(∂L/∂x) in the
// scaled variables (each variable moves by η sᵢ), for the test that adds a rule to the catalogue.
#pragma once

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad::testing {

struct SignDescentOptions {
  double lr = 0.1;  // η > 0, the distance every free variable moves (in z)

  static const OptionList<SignDescentOptions>& descriptors() {
    static const OptionList<SignDescentOptions> options = {
        rule_option("lr", &SignDescentOptions::lr, positive(),
                    "distance η every variable moves, in its scale"),
    };
    return options;
  }
};

class SignDescent final : public Optimizer {
 public:
  using Options = SignDescentOptions;
  // Its rule in the catalogue once added (add_direct_rule<SignDescent>()); a colour no built-in
  // rule has.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "sign", .label = "Sign descent", .formula = "Δx = −η sign(∂L/∂x)",
         .colour = "#3b7a57"},
    };
    return list;
  }
  explicit SignDescent(Options options = {}) : options_(checked("sign", options)) {}
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override {
    const Vector s = domain.scale(x.size());
    const Vector dx = -options_.lr * s.cwiseProduct(objective.gradient(x).cwiseSign());
    return {domain.feasible_step(x, dx), Step::Status::kOk, {}, 1};
  }
  Options options_;
};

}  // namespace physgrad::testing
