// SgdUpdate — stochastic gradient descent on network weights: Δθ = −η ∇θ of the batch-mean loss,
// backpropagated through physics and network.
#pragma once

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct SgdOptions {
  double lr = 1e-2;  // η > 0

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<SgdOptions>& descriptors();
};

class SgdUpdate final : public LearningUpdate {
 public:
  using Options = SgdOptions;
  explicit SgdUpdate(Options options = {});
  std::string id() const override { return "sgd"; }
  nlohmann::json params() const override { return {{"lr", options_.lr}}; }
  UpdateNeed need() const override { return UpdateNeed::kGradient; }
  Step step(const BatchState& batch) override { return {-options_.lr * batch.gradient}; }
  double learning_rate() const override { return options_.lr; }
  void set_learning_rate(double lr) override;

 private:
  Options options_;
};

}  // namespace physgrad
