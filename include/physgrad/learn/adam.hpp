// AdamUpdate — Adam on network weights: the moments of optim/adam.hpp (m̂, v̂ bias-corrected)
// applied to ∇θ of the batch-mean loss, Δθ = −η m̂/(√v̂ + ε).
#pragma once

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/optim/adam.hpp"

namespace physgrad {

class AdamUpdate final : public LearningUpdate {
 public:
  using Options = AdamOptions;
  explicit AdamUpdate(Options options = {}) : state_(options) {}
  std::string id() const override { return "adam"; }
  nlohmann::json params() const override { return state_.params(); }
  UpdateNeed need() const override { return UpdateNeed::kGradient; }
  void reset() override { state_.reset(); }
  Step step(const BatchState& batch) override { return {state_.update(batch.gradient)}; }
  double learning_rate() const override { return state_.options().lr; }
  void set_learning_rate(double lr) override { state_.set_learning_rate(lr); }
  nlohmann::json state() const override { return state_.state(); }
  void restore(const nlohmann::json& state, Index parameter_count) override {
    state_.restore(state, parameter_count);
  }

 private:
  AdamState state_;
};

}  // namespace physgrad
