#include "physgrad/learn/schedule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

namespace {

constexpr NameTable<ScheduleKind, 4> kScheduleNames{{
    {ScheduleKind::kConstant, "constant"},
    {ScheduleKind::kStep, "step"},
    {ScheduleKind::kCosine, "cosine"},
    {ScheduleKind::kPlateau, "plateau"},
}};

// An option of the schedule group (OptionGroup) that applies to the schedules `kinds` only.
template <class... Kinds>
RuleOption<ScheduleOptions> for_kinds(RuleOption<ScheduleOptions> option, Kinds... kinds) {
  option.applies = [=](const ScheduleOptions& o) { return ((o.schedule == kinds) || ...); };
  return in_group(OptionGroup::kSchedule, std::move(option));
}

}  // namespace

std::string to_string(ScheduleKind kind) { return name_of(kScheduleNames, kind, "ScheduleKind"); }

const OptionList<ScheduleOptions>& ScheduleOptions::descriptors() {
  using K = ScheduleKind;
  static const OptionList<ScheduleOptions> options = {
      in_group(OptionGroup::kSchedule,
               rule_option("schedule", &ScheduleOptions::schedule,
                           {K::kConstant, K::kStep, K::kCosine, K::kPlateau},
                           "step-size schedule, as torch.optim.lr_scheduler: constant, step "
                           "(StepLR), cosine (CosineAnnealingLR), plateau (ReduceLROnPlateau on "
                           "the evaluated training loss)")),
      for_kinds(rule_option("decay", &ScheduleOptions::decay, open_fraction(),
                            "factor γ of each decay (step, plateau)"),
                K::kStep, K::kPlateau),
      for_kinds(rule_option("decay_every", &ScheduleOptions::decay_every, integer_at_least(1),
                            "updates between two decays (step)"),
                K::kStep),
      for_kinds(rule_option("t_max", &ScheduleOptions::t_max, integer_at_least(1),
                            "updates from η down to min_lr (cosine; min_lr after them)"),
                K::kCosine),
      for_kinds(rule_option("min_lr", &ScheduleOptions::min_lr, non_negative(),
                            "the smallest step size (cosine, plateau)"),
                K::kCosine, K::kPlateau),
      for_kinds(rule_option("patience", &ScheduleOptions::patience, integer_at_least(0),
                            "evaluations without improvement before a decay (plateau)"),
                K::kPlateau),
      for_kinds(rule_option("threshold", &ScheduleOptions::threshold, fraction(),
                            "relative improvement of the best loss that counts (plateau)"),
                K::kPlateau),
  };
  return options;
}

LearningRateSchedule::LearningRateSchedule(ScheduleOptions options)
    : options_(checked("schedule", options)) {
  reset();
}

void LearningRateSchedule::reset() {
  updates_ = 0;
  best_ = std::numeric_limits<double>::infinity();
  stalled_ = 0;
  decays_ = 0;
}

double LearningRateSchedule::rate(double base) const {
  const ScheduleOptions& o = options_;
  switch (o.schedule) {
    case ScheduleKind::kConstant: return base;
    case ScheduleKind::kStep:
      return base * std::pow(o.decay, static_cast<double>(updates_ / o.decay_every));
    case ScheduleKind::kCosine: {
      const double t = std::min(static_cast<double>(updates_), static_cast<double>(o.t_max));
      const double floor = std::min(o.min_lr, base);
      return floor + (base - floor) * (1 + std::cos(M_PI * t / o.t_max)) / 2;
    }
    case ScheduleKind::kPlateau:
      return std::max(base * std::pow(o.decay, static_cast<double>(decays_)),
                      std::min(o.min_lr, base));
  }
  return base;
}

void LearningRateSchedule::observe(double loss) {
  if (options_.schedule != ScheduleKind::kPlateau || !std::isfinite(loss)) return;
  if (loss < (1 - options_.threshold) * best_) {
    best_ = loss;
    stalled_ = 0;
  } else if (++stalled_ > options_.patience) {
    ++decays_;
    stalled_ = 0;
  }
}

nlohmann::json LearningRateSchedule::state() const {
  if (constant()) return nullptr;
  return {{"updates", updates_},
          {"best", std::isfinite(best_) ? nlohmann::json(best_) : nlohmann::json()},
          {"stalled", stalled_},
          {"decays", decays_}};
}

void LearningRateSchedule::restore(const nlohmann::json& state) {
  reset();
  if (constant()) {
    if (!state.is_null()) throw Error("checkpoint: a constant schedule has no state");
    return;
  }
  if (!state.is_object()) throw Error("checkpoint: the schedule's state is not an object");
  updates_ = integer_from_json(state, "updates");
  best_ = real_from_json(state, "best", true);
  if (std::isnan(best_)) best_ = std::numeric_limits<double>::infinity();
  stalled_ = integer_from_json(state, "stalled");
  decays_ = integer_from_json(state, "decays");
}

}  // namespace physgrad
