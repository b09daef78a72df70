// SgdUpdate — stochastic gradient descent on network weights: Δθ = −η_t ∇θ of the batch-mean loss,
// backpropagated through physics and network, with η_t from a schedule (learn/schedule.hpp).
#pragma once

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/learn/schedule.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct SgdOptions {
  double lr = 1e-2;  // η > 0
  ScheduleOptions schedule;

  // Each option once: name, member, range, help (params(), settings by name, validation).
  static const OptionList<SgdOptions>& descriptors();
};

class SgdUpdate final : public LearningUpdate {
 public:
  using Options = SgdOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "sgd", .label = "SGD", .formula = "Δθ = −η ∇θL", .colour = "#6baed6"},
    };
    return list;
  }
  explicit SgdUpdate(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }
  UpdateNeed need() const override { return UpdateNeed::kGradient; }
  void reset() override { schedule_.reset(); }
  Step step(const BatchState& batch) override;
  // The base step size η (the schedule scales it).
  double learning_rate() const override { return options_.lr; }
  void set_learning_rate(double lr) override;
  nlohmann::json state() const override { return schedule_.state(); }
  void restore(const nlohmann::json& state, Index /*parameter_count*/) override {
    schedule_.restore(state);
  }
  void observe(const Evaluation& evaluation) override { schedule_.observe(evaluation.train_loss); }

 private:
  Options options_;
  LearningRateSchedule schedule_;
};

}  // namespace physgrad
