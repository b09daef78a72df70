// Adam: m ← β₁m + (1−β₁)g, v ← β₂v + (1−β₂)g², Δx = −η m̂ / (√v̂ + ε) with bias-corrected
// m̂ = m/(1−β₁ᵗ), v̂ = v/(1−β₂ᵗ); a diagonal (per-component) rescaling of the gradient.
#pragma once

#include <nlohmann/json.hpp>

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct AdamOptions {
  double lr = 1e-3;      // η > 0
  double beta1 = 0.9;    // 0 ≤ β₁ < 1
  double beta2 = 0.999;  // 0 ≤ β₂ < 1
  double epsilon = 1e-8; // ε > 0

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<AdamOptions>& descriptors();
};

// The moment update on a given gradient, shared by direct optimization and network training.
class AdamState {
 public:
  using Options = AdamOptions;
  explicit AdamState(Options options = {});
  const Options& options() const { return options_; }
  nlohmann::json params() const;  // lr, beta1, beta2, epsilon
  void set_learning_rate(double lr);
  void reset();
  Vector update(const Vector& gradient);  // returns Δ = −η m̂ / (√v̂ + ε)
  // The moments and step count, and their restoration (throws Error on a malformed state or
  // one of another size than `size`).
  nlohmann::json state() const;
  void restore(const nlohmann::json& state, Index size);

 private:
  Options options_;
  Vector m_, v_;
  long long t_ = 0;
};

class Adam final : public Optimizer {
 public:
  using Options = AdamOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "adam", .label = "Adam", .formula = "Δx = −η m̂/(√v̂ + ε)", .colour = "#ff7f0e"},
    };
    return list;
  }
  explicit Adam(Options options = {}) : state_(options) {}
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return state_.params(); }
  void reset() override { state_.reset(); }

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) override;
  AdamState state_;
};

}  // namespace physgrad
