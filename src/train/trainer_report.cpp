// The words of a training run: its termination's names, its epochs, and the brief and full
// reports of a TrainingSummary.
#include <algorithm>
#include <cmath>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"
#include "physgrad/train/trainer.hpp"

namespace physgrad {

namespace {

constexpr NameTable<TrainingTermination, 6> kTerminationNames{{
    {TrainingTermination::kMaxIterations, "max_iterations"},
    {TrainingTermination::kMaxEpochs, "max_epochs"},
    {TrainingTermination::kTimeBudget, "time_budget"},
    {TrainingTermination::kNumericalFailure, "numerical_failure"},
    {TrainingTermination::kInterrupted, "interrupted"},
    {TrainingTermination::kDiverged, "diverged"},
}};

}  // namespace

std::string to_string(TrainingTermination termination) {
  return name_of(kTerminationNames, termination, "TrainingTermination");
}

TrainingTermination parse_training_termination(const std::string& text) {
  return value_named(kTerminationNames, text, "training termination");
}

bool ended_by_limit(TrainingTermination termination) {
  return termination == TrainingTermination::kMaxIterations ||
         termination == TrainingTermination::kMaxEpochs ||
         termination == TrainingTermination::kTimeBudget;
}

double epochs_done(const TrainingSummary& s) {
  if (s.samples <= 0) return 0.0;
  double seen = 0;
  for (std::size_t p = 0; p < s.phases.size(); ++p) {
    const long long end =
        p + 1 < s.phases.size() ? s.phases[p + 1].first_iteration : s.iterations;
    seen += static_cast<double>(std::max(0LL, end - s.phases[p].first_iteration)) *
            static_cast<double>(s.phases[p].batch_size);
  }
  return seen / static_cast<double>(s.samples);
}

std::string brief_report(const TrainingSummary& s) {
  const double initial = s.history.empty() ? NAN : s.history.front().train_loss;
  const double final_loss = s.history.empty() ? NAN : s.history.back().train_loss;
  std::string parts;
  for (std::size_t p = 1; p < s.phases.size(); ++p) {
    parts += ", part " + std::to_string(p + 1) + " from iteration " +
             std::to_string(s.phases[p].first_iteration);
  }
  return s.update + ": " + std::to_string(s.iterations) + " iterations (" +
         report_number(epochs_done(s)) + " epochs" + parts + "), " +
         std::to_string(s.counts.passes) + " simulator passes, train loss " +
         report_number(initial) + " → " + report_number(final_loss) + ", " +
         (s.termination ? to_string(*s.termination) : std::string("in progress"));
}

std::string full_report(const TrainingSummary& s) {
  std::string out = "physgrad training report\n\nProblem\n";
  out += report_row("parameters", std::to_string(s.parameters));
  out += report_row(s.fresh_samples ? "samples per epoch (drawn afresh)" : "training samples",
                    std::to_string(s.samples));
  for (std::size_t p = 0; p < s.phases.size(); ++p) {
    out += report_row(s.phases.size() == 1 ? "batch size"
                                           : "batch size from iteration " +
                                                 std::to_string(s.phases[p].first_iteration),
                      std::to_string(s.phases[p].batch_size));
  }
  out += "\nRule\n";
  out += report_row("update", s.update);
  for (const auto& [name, value] : s.params.items()) {
    out += report_row(name, value.is_string() ? value.get<std::string>() : value.dump());
  }
  out += "\nLimits\n";
  for (const auto& [name, value] : s.limits) out += report_row(name, report_number(value));
  if (!s.history.empty()) {
    const TrainingRecord& first = s.history.front();
    const TrainingRecord& last = s.history.back();
    out += "\nLoss (train, test)\n";
    const auto losses = [](const TrainingRecord& r) {
      return report_number(r.train_loss) + ", " + report_number(r.test_loss);
    };
    out += report_row("initial", losses(first));
    out += report_row("final (iteration " + std::to_string(last.iteration) + ")", losses(last));
    out += report_row("change (train)", report_number(first.train_loss - last.train_loss));
  }
  out += "\nWork\n";
  out += report_row("iterations", std::to_string(s.iterations));
  out += report_row("epochs", report_number(epochs_done(s)));
  out += report_row("evaluations", std::to_string(s.history.size()));
  out += report_row("step halvings", std::to_string(s.step_halvings));
  out += report_row("simulator passes", std::to_string(s.counts.passes));
  for (const auto& [name, field] : SimulatorCounts::fields()) {
    if (field == &SimulatorCounts::passes) continue;
    out += report_row("  " + std::string(name), std::to_string(s.counts.*field));
  }
  out += "\nTime (seconds)\n";
  out += report_row("network + physics", report_number(s.forward_seconds));
  out += report_row("derivatives", report_number(s.derivative_seconds));
  out += report_row("inversion", report_number(s.inversion_seconds));
  out += report_row("rest of the update", report_number(s.update_seconds));
  out += report_row("training", report_number(s.train_seconds));
  out += report_row("run (with evaluations)", report_number(s.wall_seconds));
  out += "\nTermination: " +
         (s.termination ? to_string(*s.termination) : std::string("in progress")) +
         (s.message.empty() ? "" : " (" + s.message + ")") + "\n";
  return out;
}

}  // namespace physgrad
