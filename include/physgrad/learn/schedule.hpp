// Learning-rate schedule — the step size of a first-order rule over training, as
// torch.optim.lr_scheduler offers them: η_t = η·γ^⌊t/s⌋ (step), η_min + (η − η_min)(1 + cos(π·t/T))/2
// (cosine, t ≤ T), or η times γ each time the evaluated loss stalls for `patience` evaluations (plateau).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "physgrad/rule_option.hpp"

namespace physgrad {

enum class ScheduleKind { kConstant, kStep, kCosine, kPlateau };
// "constant", "step", "cosine", "plateau".
std::string to_string(ScheduleKind kind);

// torch's names in brackets: StepLR(step_size, gamma), CosineAnnealingLR(T_max, eta_min),
// ReduceLROnPlateau(factor, patience, threshold (relative), min_lr); patience counts
// evaluations, not epochs. Only the options of the chosen kind apply.
struct ScheduleOptions {
  ScheduleKind schedule = ScheduleKind::kConstant;
  double decay = 0.1;          // γ of step and plateau [gamma, factor]
  int decay_every = 1000;      // step: updates between decays [step_size]
  int t_max = 10000;           // cosine: updates to the minimum [T_max]
  double min_lr = 0;           // cosine and plateau: the floor [eta_min, min_lr]
  int patience = 10;           // plateau: evaluations without improvement before a decay
  double threshold = 1e-4;     // plateau: an improvement counts when below (1 − threshold)·best

  static const OptionList<ScheduleOptions>& descriptors();
};

// The schedule's state over one run: the updates made and, for plateau, the best evaluated loss,
// the evaluations since it improved and the decays so far.
class LearningRateSchedule {
 public:
  explicit LearningRateSchedule(ScheduleOptions options = {});
  const ScheduleOptions& options() const { return options_; }
  bool constant() const { return options_.schedule == ScheduleKind::kConstant; }
  // The step size of the next update for base step size `base` (exactly `base` when constant).
  double rate(double base) const;
  // An update was made.
  void advance() { ++updates_; }
  // An evaluated loss (plateau: may decay the rate).
  void observe(double loss);
  void reset();
  // Empty for a constant schedule; restore() throws Error on a malformed state.
  nlohmann::json state() const;
  void restore(const nlohmann::json& state);

 private:
  ScheduleOptions options_;
  long long updates_ = 0;
  double best_;
  long long stalled_ = 0;
  long long decays_ = 0;
};

}  // namespace physgrad
