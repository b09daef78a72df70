// The parts of a twin as LearningSweep runs them: the options of its Adam part (--pretrain-lr, …),
// the control arm Adam→Adam beside the twins, and each part's training seconds per update.
#include <algorithm>
#include <cmath>

#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/run/cases/learning_runs.hpp"

namespace physgrad::run {

namespace {

// The control's default step over the Adam part's (--control-lr-factor unset).
constexpr double kControlLrFactor = 0.1;

// "lr ×0.1" of the control's params; empty for any other run.
std::string control_step_text(const std::string& id, const nlohmann::json& params) {
  if (!is_control_run(id) || !params.contains("control_lr_factor")) return {};
  return "lr ×" + format_value(params.at("control_lr_factor").get<double>());
}

}  // namespace

bool is_control_run(const std::string& id) { return pretrained_rule(id) == kPretrainingRule; }

std::string run_rule_label(const std::string& id, const nlohmann::json& params) {
  const std::string step = control_step_text(id, params);
  return learning_run_label(id) + (step.empty() ? "" : " (" + step + ")");
}

std::string taking_over_label(const std::string& id, const nlohmann::json& params) {
  const std::string step = control_step_text(id, params);
  return learning_run_label(pretrained_rule(id)) + (step.empty() ? "" : " at " + step);
}

double PhaseCost::seconds_per_update() const {
  return updates > 0 ? seconds / static_cast<double>(updates) : NAN;
}

double rule_seconds_per_update(const LearningResult& run) {
  const TrainingSummary& s = run.summary;
  if (!run.params.contains("pretrain_iterations")) {
    return s.iterations > 0 ? s.train_seconds / static_cast<double>(s.iterations) : NAN;
  }
  // A twin: from its own evaluations after the switch (one is made where the rule takes over).
  const double from = run.params.at("pretrain_iterations").get<double>();
  const auto first = std::find_if(s.history.begin(), s.history.end(), [&](const TrainingRecord& r) {
    return static_cast<double>(r.iteration) >= from;
  });
  if (first == s.history.end() || s.history.back().iteration <= first->iteration) return NAN;
  return (s.history.back().train_seconds - first->train_seconds) /
         static_cast<double>(s.history.back().iteration - first->iteration);
}

double adam_updates_per_update(const LearningResult& run) {
  const std::string rule = pretrained_rule(run.id);
  if (run.id == kPretrainingRule || rule == kPretrainingRule) return 1;
  const std::vector<TrainingSummary::Phase>& phases = run.summary.phases;
  if (phases.empty() || (!rule.empty() && phases.size() < 2)) return NAN;
  return phases.back().reference_updates();
}

std::vector<PhaseCost> phase_costs(const LearningResult& run) {
  if (!run.params.contains("switched")) return {};
  const TrainingSummary& s = run.summary;
  if (run.params.at("switched") != true) {
    return {{kPretrainingRule, s.iterations, s.train_seconds, 1}};
  }
  // The trainer evaluates where the rule takes over, before its first update.
  const long long at = run.params.at("pretrain_iterations").get<long long>();
  double adam_seconds = NAN;
  for (const TrainingRecord& r : s.history) {
    if (r.iteration == at) {
      adam_seconds = r.train_seconds;
      break;
    }
  }
  return {{kPretrainingRule, at, adam_seconds, 1},
          {pretrained_rule(run.id), s.iterations - at, s.train_seconds - adam_seconds,
           adam_updates_per_update(run)}};
}

RuleSettings LearningSweep::pretraining_settings() const {
  RuleSettings settings;
  for (const OptionDescription& option :
       rule_options(find_rule(RuleKind::kLearning, kPretrainingRule))) {
    const std::string flag = "pretrain-" + flag_name(option.name);
    if (settings_.has(flag)) settings[option.name] = settings_.json().at(flag);
  }
  return settings;
}

std::optional<double> LearningSweep::control_factor() const {
  if (settings_.has("control") && settings_.text("control") == "off") return std::nullopt;
  const double factor =
      settings_.has("control-lr-factor") ? settings_.real("control-lr-factor") : kControlLrFactor;
  if (!(factor > 0)) return std::nullopt;
  return factor;
}

bool LearningSweep::rules_alone() const {
  return !(settings_.has("alone") && settings_.text("alone") == "off");
}

}  // namespace physgrad::run
