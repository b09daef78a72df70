#include "physgrad/optim/minimize.hpp"

#include <sstream>
#include <string_view>

#include "physgrad/text.hpp"

namespace physgrad {

std::string to_string(Termination termination) {
  switch (termination) {
    case Termination::kConverged: return "converged";
    case Termination::kRelativeLoss: return "relative_loss";
    case Termination::kGradientTolerance: return "gradient_tolerance";
    case Termination::kFunctionTolerance: return "function_tolerance";
    case Termination::kParameterTolerance: return "parameter_tolerance";
    case Termination::kDiverged: return "diverged";
    case Termination::kMaxIterations: return "max_iterations";
    case Termination::kMaxEvaluations: return "max_evaluations";
    case Termination::kMaxSeconds: return "max_seconds";
    case Termination::kStationary: return "stationary";
    case Termination::kNumericalFailure: return "numerical_failure";
    case Termination::kFailed: return "failed";
    case Termination::kStopped: return "stopped";
  }
  return "unknown";
}

bool converged(Termination termination) {
  switch (termination) {
    case Termination::kConverged:
    case Termination::kRelativeLoss:
    case Termination::kGradientTolerance:
    case Termination::kFunctionTolerance:
    case Termination::kParameterTolerance: return true;
    default: return false;
  }
}

std::string brief_report(const MinimizeSummary& s) {
  return s.optimizer + ": " + std::to_string(s.iterations) + " iterations, " +
         std::to_string(s.evaluations) + " evaluations, " + std::to_string(s.counts.passes) +
         " simulator passes, loss " + report_number(s.initial_loss) + " → " + report_number(s.loss) + ", " +
         to_string(s.termination);
}

std::string full_report(const MinimizeSummary& s) {
  std::ostringstream out;
  const auto row = [&out](std::string_view name, const std::string& value) {
    out << report_row(name, value);
  };
  out << "physgrad minimize report\n\n";
  out << "Problem\n";
  row("parameters", std::to_string(s.parameters));
  row("bounds", s.bounded ? "box (" + std::to_string(s.at_bounds) + " at a bound at the end)"
                          : "none");
  row("x_scale", s.scaled ? "given" : "none (1)");
  out << "\nRule\n";
  row("optimizer", s.optimizer);
  for (const auto& [name, value] : s.params.items()) {
    row(name, value.is_string() ? value.get<std::string>() : value.dump());
  }
  out << "\nStopping rules and budgets\n";
  for (const auto& [name, value] : s.stopping_rules) row(name, report_number(value));
  out << "\nLoss\n";
  row("initial", report_number(s.initial_loss));
  row("final", report_number(s.loss));
  row("change", report_number(s.initial_loss - s.loss));
  if (s.gradient_norm >= 0) row("projected gradient", report_number(s.gradient_norm));
  out << "\nWork\n";
  row("iterations", std::to_string(s.iterations) + " (" + std::to_string(s.rejected_steps) +
                        " rejected trials)");
  row("evaluations", std::to_string(s.evaluations) + " (of the loss)");
  if (s.history_dropped > 0) {
    row("history", std::to_string(s.history.size()) + " records kept, " +
                       std::to_string(s.history_dropped) + " dropped (max_history)");
  }
  row("simulator passes", std::to_string(s.counts.passes));
  row("  forward samples", std::to_string(s.counts.forward));
  row("  VJP samples", std::to_string(s.counts.vjp));
  row("  Jacobians", std::to_string(s.counts.jacobians));
  row("  Hessians", std::to_string(s.counts.hessians));
  row("  time reversals", std::to_string(s.counts.reversals));
  row("  inverses", std::to_string(s.counts.inverses));
  out << "\nTime (seconds)\n";
  row("rule steps", report_number(s.step_seconds));
  row("loss evaluations", report_number(s.evaluation_seconds));
  row("total", report_number(s.wall_seconds));
  out << "\nTermination: " << to_string(s.termination)
      << (converged(s.termination) ? " (convergence)" : "") << "\n";
  if (!s.message.empty()) out << "  " << s.message << "\n";
  return out.str();
}

}  // namespace physgrad
