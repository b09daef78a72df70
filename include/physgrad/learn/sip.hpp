// SipUpdate — scale-invariant physics training: per sample x̃ᵢ = P⁻¹(yᵢ + η Δyᵢ; xᵢ), Δy the Newton
// step of the loss in y (y* − y for L2), then Adam on the proxy loss mean ½‖xᵢ − x̃ᵢ‖², x̃ constant.
#pragma once

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/optim/adam.hpp"
#include "physgrad/optim/local_inverse.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct SipOptions {
  AdamOptions adam{};           // the first-order rule on the proxy loss (lr = η_NN)
  double y_step = 1.0;          // η > 0: fraction of the Newton step in y
  LocalInverseOptions inverse{};  // the simulator's own inverse when it has one (auto)

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<SipOptions>& descriptors();
};

// The proxy gradient is the cotangent (xᵢ − x̃ᵢ)/B backpropagated through the network. A sample
// whose local inverse fails (non-finite, or a NumericalError) gets a NaN cotangent, so the
// whole step is non-finite on every rank and Step::message says which sample and why.
class SipUpdate final : public LearningUpdate {
 public:
  using Options = SipOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "sip", .label = "SIP", .formula = "x̃ = P⁻¹(y + ηΔy; x), Adam on ½‖f(in; θ) − x̃‖²",
         .colour = "#000000"},
    };
    return list;
  }
  explicit SipUpdate(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override;
  UpdateNeed need() const override { return UpdateNeed::kNetworkOutputs; }
  void reset() override { adam_.reset(); }
  Step step(const BatchState& batch) override;
  double learning_rate() const override { return adam_.options().lr; }
  void set_learning_rate(double lr) override;
  nlohmann::json state() const override { return adam_.state(); }
  void restore(const nlohmann::json& state, Index parameter_count) override {
    adam_.restore(state, parameter_count);
  }

 private:
  Options options_;  // adam.lr follows set_learning_rate
  AdamState adam_;
};

}  // namespace physgrad
