// SwitchingUpdate — one run made by two rules in turn, as the HIG paper trains with Adam before
// HIG: `first` makes the updates until the switch, then `second` continues from that network.
#pragma once

#include <memory>
#include <vector>

#include "physgrad/learn/learning_update.hpp"

namespace physgrad {

// When the first rule hands over: after `after` updates, or (after = 0) once the evaluated
// training loss has levelled off — the best of the last `window` evaluations is less than
// `fraction` below the best of all evaluations before them.
struct SwitchCondition {
  long long after = 0;
  int window = 10;
  double fraction = 0.02;

  bool on_plateau() const { return after == 0; }
  // "after 2000 updates" or "on a plateau (< 2 % over 10 evaluations)".
  std::string text() const;
};

// Whether the evaluated losses `losses` (oldest first) have levelled off under `condition`.
bool levelled_off(const std::vector<double>& losses, const SwitchCondition& condition);

class SwitchingUpdate final : public LearningUpdate {
 public:
  // Each part with the batch size it trains with. Throws Error for a missing part, a batch size
  // < 1, a window < 1 or a fraction outside (0, 1).
  SwitchingUpdate(std::unique_ptr<LearningUpdate> first, Index first_batch,
                  std::unique_ptr<LearningUpdate> second, Index second_batch,
                  SwitchCondition condition);

  // "adam-hig": the parts' ids.
  std::string id() const override;
  std::string part_id() const override { return current().part_id(); }
  // The second rule's params(), the first's as "pretrain_<name>", its batch as "pretrain_batch"
  // and the condition: "pretrain_iterations" (after) or "pretrain_window"/"pretrain_fraction".
  nlohmann::json params() const override;
  UpdateNeed need() const override { return current().need(); }
  void reset() override;
  Step step(const BatchState& batch) override;
  double learning_rate() const override { return current().learning_rate(); }
  void set_learning_rate(double lr) override { current().set_learning_rate(lr); }
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state, Index parameter_count) override;
  bool steps_can_be_halved() const override { return current().steps_can_be_halved(); }
  nlohmann::json step_info() const override { return current().step_info(); }
  void observe(const Evaluation& evaluation) override;
  int phase() const override { return switched_at_ >= 0 ? 1 : 0; }
  std::optional<Index> batch_size() const override {
    return switched_at_ >= 0 ? second_batch_ : first_batch_;
  }

  const LearningUpdate& first() const { return *first_; }
  const LearningUpdate& second() const { return *second_; }
  const SwitchCondition& condition() const { return condition_; }
  // The updates the first rule made before the second took over; −1 while it has not.
  long long switched_at() const { return switched_at_; }

 private:
  LearningUpdate& current() const { return switched_at_ >= 0 ? *second_ : *first_; }

  std::unique_ptr<LearningUpdate> first_, second_;
  Index first_batch_, second_batch_;
  SwitchCondition condition_;
  long long steps_ = 0;        // updates made so far, by either part
  long long switched_at_ = -1;
  std::vector<double> losses_;  // evaluated training losses while the first rule trains
};

}  // namespace physgrad
