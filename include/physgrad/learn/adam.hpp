// AdamUpdate — Adam on network weights: the moments of optim/adam.hpp (m̂, v̂ bias-corrected)
// applied to ∇θ of the batch-mean loss, Δθ = −η_t m̂/(√v̂ + ε), η_t from a schedule (schedule.hpp).
#pragma once

#include "physgrad/learn/learning_update.hpp"
#include "physgrad/learn/schedule.hpp"
#include "physgrad/optim/adam.hpp"

namespace physgrad {

// Adam's options and the schedule of its step size.
struct LearningAdamOptions {
  AdamOptions adam;
  ScheduleOptions schedule;

  static const OptionList<LearningAdamOptions>& descriptors();
};

class AdamUpdate final : public LearningUpdate {
 public:
  using Options = LearningAdamOptions;
  // Its rule in the catalogue (catalogue.hpp): id, label, formula, colour, defaults.
  static const RuleDescriptors<Options>& rules() {
    static const RuleDescriptors<Options> list = {
        {.id = "adam", .label = "Adam", .formula = "Δθ = −η m̂/(√v̂ + ε) on ∇θL",
         .colour = "#ff7f0e", .pretrained_colour = "#e6ab02"},
    };
    return list;
  }
  explicit AdamUpdate(Options options = {});
  std::string id() const override { return rules().front().id; }
  nlohmann::json params() const override { return option_values(options_); }
  UpdateNeed need() const override { return UpdateNeed::kGradient; }
  void reset() override;
  Step step(const BatchState& batch) override;
  // The base step size η (the schedule scales it).
  double learning_rate() const override { return options_.adam.lr; }
  void set_learning_rate(double lr) override;
  // The moments, with the schedule's state when it is not constant.
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state, Index parameter_count) override;
  void observe(const Evaluation& evaluation) override { schedule_.observe(evaluation.train_loss); }

 private:
  Options options_;
  AdamState moments_;
  LearningRateSchedule schedule_;
};

}  // namespace physgrad
