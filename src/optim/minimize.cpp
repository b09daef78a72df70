#include "physgrad/optim/minimize.hpp"

#include <algorithm>
#include <chrono>
#include <deque>
#include <iterator>
#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"
#include "physgrad/timing.hpp"

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

namespace {

void check_minimize_options(const MinimizeOptions& options) {
  if (options.max_iterations < 1) {
    throw Error("minimize: max_iterations must be ≥ 1, got " +
                std::to_string(options.max_iterations));
  }
  if (options.max_evaluations < 0) {
    throw Error("minimize: max_evaluations must be ≥ 0 (0: no budget), got " +
                std::to_string(options.max_evaluations));
  }
  if (options.max_history < 2 || options.max_history_values < 2) {
    throw Error("minimize: max_history and max_history_values must be ≥ 2, got " +
                std::to_string(options.max_history) + " and " +
                std::to_string(options.max_history_values));
  }
  const double inf = INFINITY;
  require_in_range("minimize: max_seconds", options.max_seconds, 0.0, inf);
  require_in_range("minimize: loss_tolerance", options.loss_tolerance, 0.0, inf);
  require_in_range("minimize: relative_loss_tolerance", options.relative_loss_tolerance, 0.0, 1.0);
  require_in_range("minimize: gradient_tolerance", options.gradient_tolerance, 0.0, inf);
  require_in_range("minimize: function_tolerance", options.function_tolerance, 0.0, inf);
  require_in_range("minimize: parameter_tolerance", options.parameter_tolerance, 0.0, inf);
}

// The stopping rules of one run. Each test returns the termination that holds, with its
// message; comparisons are written so that NaN never passes (a <= b is false for NaN).
class StoppingRules {
 public:
  StoppingRules(const MinimizeOptions& options, const Domain& domain, double initial_loss)
      : options_(options), domain_(domain), initial_loss_(initial_loss) {}

  // The tests on the current point: loss, relative loss, projected gradient (when `gradient`
  // is given).
  bool at_point(double loss, const Vector& x, const Vector* gradient, MinimizeSummary& out) const {
    if (std::isfinite(loss) && loss <= options_.loss_tolerance) {
      return stop(out, Termination::kConverged,
                  "L = " + report_number(loss) + " ≤ loss_tolerance = " + report_number(options_.loss_tolerance));
    }
    const double relative = options_.relative_loss_tolerance * initial_loss_;
    if (options_.relative_loss_tolerance > 0 && std::isfinite(loss) && loss <= relative) {
      return stop(out, Termination::kRelativeLoss,
                  "L = " + report_number(loss) + " ≤ relative_loss_tolerance·L₀ = " + report_number(relative));
    }
    if (gradient != nullptr) {
      out.gradient_norm = domain_.projected_gradient_norm(x, *gradient);
      if (std::isfinite(out.gradient_norm) && out.gradient_norm <= options_.gradient_tolerance) {
        return stop(out, Termination::kGradientTolerance,
                    "projected gradient max-norm " + report_number(out.gradient_norm) +
                        " ≤ gradient_tolerance = " + report_number(options_.gradient_tolerance));
      }
    }
    return false;
  }

  // The tests on a step from x (loss `before`) by dx to loss `after`; the function tolerance
  // only when the step was taken (`moved`).
  bool after_step(double before, double after, const Vector& x, const Vector& dx,
                  MinimizeSummary& out, bool moved = true) const {
    const double change = std::abs(before - after);
    const double allowed = options_.function_tolerance * before;
    if (moved && options_.function_tolerance > 0 && std::isfinite(change) && change <= allowed) {
      return stop(out, Termination::kFunctionTolerance,
                  "|ΔL| = " + report_number(change) + " ≤ function_tolerance·L = " + report_number(allowed));
    }
    const double tol = options_.parameter_tolerance;
    const double length = domain_.scaled_norm(dx);
    const double limit = tol * (domain_.scaled_norm(x) + tol);
    if (tol > 0 && std::isfinite(length) && length <= limit) {
      return stop(out, Termination::kParameterTolerance,
                  std::string(moved ? "step" : "rejected trial") + " ‖Δx ⊘ s‖ = " + report_number(length) +
                      " ≤ parameter_tolerance·(‖x ⊘ s‖ + parameter_tolerance) = " + report_number(limit));
    }
    return false;
  }

  std::vector<std::pair<std::string, double>> listed() const {
    std::vector<std::pair<std::string, double>> rules = {
        {"max_iterations", options_.max_iterations}, {"loss_tolerance", options_.loss_tolerance}};
    for (const auto& [name, value] :
         {std::pair{"relative_loss_tolerance", options_.relative_loss_tolerance},
          std::pair{"gradient_tolerance", options_.gradient_tolerance},
          std::pair{"function_tolerance", options_.function_tolerance},
          std::pair{"parameter_tolerance", options_.parameter_tolerance},
          std::pair{"max_evaluations", static_cast<double>(options_.max_evaluations)},
          std::pair{"max_seconds", options_.max_seconds}}) {
      if (value > 0) rules.emplace_back(name, value);
    }
    return rules;
  }

 private:
  static bool stop(MinimizeSummary& out, Termination termination, std::string message) {
    out.termination = termination;
    out.message = std::move(message);
    return true;
  }

  const MinimizeOptions& options_;
  const Domain& domain_;
  double initial_loss_;
};

}  // namespace

MinimizeSummary minimize(Optimizer& optimizer, const Objective& objective, const Vector& x0,
                         const MinimizeOptions& options) {
  check_minimize_options(options);
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  // Everything below reaches the simulator through `problem`, whose simulator is checked and
  // counted (a nested run, pg's local inverse, shares the outer run's CheckedSimulator).
  const CheckedObjective checked(objective);
  const Objective& problem = checked.objective();
  const CheckedSimulator& simulator = checked.simulator();
  const SimulatorCounts counts_at_start = simulator.counts();

  const Domain domain(problem.dim(), options.lower, options.upper, options.x_scale);
  domain.check_dim(x0.size(), "minimize");
  domain.check_contains(x0, "minimize: x0");

  MinimizeSummary summary;
  summary.optimizer = optimizer.id();
  summary.params = optimizer.params();
  summary.parameters = x0.size();
  summary.bounded = domain.bounded();
  summary.scaled = domain.scaled();
  summary.x = x0;
  summary.termination = Termination::kMaxIterations;

  // L (and ∇L when the gradient test is on) at a point, timed as minimize's own evaluations.
  Vector gradient;
  const bool with_gradient = options.gradient_tolerance > 0;
  const auto evaluate = [&](const Vector& x) {
    const auto begin = Clock::now();
    const double value =
        with_gradient ? problem.value_and_gradient(x, gradient) : problem.value(x);
    summary.evaluation_seconds += seconds_since(begin);
    ++summary.evaluations;
    return value;
  };
  // A non-finite ∇L, where the gradient test asks for it, ends a run as a non-finite L does.
  const auto finite = [&](double value) {
    return std::isfinite(value) && (!with_gradient || all_finite(gradient));
  };
  summary.loss = evaluate(x0);
  summary.initial_loss = summary.loss;
  if (!std::isfinite(summary.loss)) {
    std::ostringstream msg;
    msg << "the loss at the starting point is " << summary.loss;
    throw Error(msg.str());
  }
  // Opened after the start: its evaluation is always made.
  const SimulatorBudget budget(simulator, options.max_evaluations, options.max_seconds,
                               counts_at_start.passes, start);
  const StoppingRules rules(options, domain, summary.initial_loss);
  summary.stopping_rules = rules.listed();
  const Vector* tested_gradient = with_gradient ? &gradient : nullptr;
  // The records kept: the start and the latest, within both limits.
  const std::size_t kept = static_cast<std::size_t>(std::max<long long>(
      2, std::min(options.max_history,
                  options.max_history_values / std::max<long long>(1, x0.size()))));
  std::deque<IterationRecord> history;  // a deque: dropping the record after the start is O(1)
  const auto record = [&](double step_norm) {
    if (history.size() >= kept) {
      history.erase(history.begin() + 1);
      ++summary.history_dropped;
    }
    history.push_back({summary.iterations, summary.loss, step_norm, seconds_since(start),
                       summary.evaluations, simulator.counts() - counts_at_start, summary.x});
    return options.callback && options.callback(history.back());
  };
  const auto end_on = [&summary](Termination termination, std::string message) {
    summary.termination = termination;
    summary.message = std::move(message);
  };

  optimizer.reset();
  bool stop = record(0.0);
  bool done = !stop && rules.at_point(summary.loss, summary.x, tested_gradient, summary);
  if (!stop && !done && !finite(summary.loss)) {
    end_on(Termination::kNumericalFailure, "the gradient at the starting point is not finite");
    done = true;
  }
  while (!stop && !done) {
    if (summary.iterations >= options.max_iterations) break;
    if (budget.out_of_time()) {
      end_on(Termination::kMaxSeconds, "max_seconds = " + report_number(options.max_seconds) +
                                           " reached after iteration " +
                                           std::to_string(summary.iterations));
      break;
    }
    // Numerical failures name the iteration, the rule and the place.
    const std::string where =
        "iteration " + std::to_string(summary.iterations + 1) + " of " + optimizer.id() + ": ";
    Step step;
    Vector x_next;
    double loss_next = NAN;
    try {
      const auto step_start = Clock::now();
      step = optimizer.step(problem, summary.x, domain);
      summary.step_seconds += seconds_since(step_start);
      summary.evaluations += step.evaluations;
      if (step.status == Step::Status::kOk && all_finite(step.delta)) {
        // The rule keeps x + Δx in the box; the projection only removes rounding in the sum.
        x_next = domain.project(summary.x + step.delta);
        if (x_next != summary.x) loss_next = evaluate(x_next);
      }
    } catch (const NumericalError& e) {
      end_on(Termination::kNumericalFailure, where + e.what());
      break;
    } catch (const BudgetExhausted& e) {
      if (e.budget() != &budget) throw;  // an outer run's budget: that run ends
      const bool passes = e.kind() == BudgetExhausted::Kind::kPasses;
      end_on(passes ? Termination::kMaxEvaluations : Termination::kMaxSeconds,
             std::string(passes ? "max_evaluations" : "max_seconds") + " reached in iteration " +
                 std::to_string(summary.iterations + 1) + ": " + e.what());
      break;
    }
    if (step.status == Step::Status::kFailed) {
      end_on(Termination::kFailed, step.message);
      break;
    }
    if (step.status == Step::Status::kRejected) {
      ++summary.iterations;
      ++summary.rejected_steps;
      stop = record(0.0);
      // A trial too short to matter ends the run like an accepted one (the loss did not move).
      done = !stop && step.delta.size() == summary.x.size() &&
             rules.after_step(summary.loss, summary.loss, summary.x, step.delta, summary, false);
      continue;
    }
    if (!all_finite(step.delta)) {
      end_on(Termination::kNumericalFailure, where + "non-finite step");
      break;
    }
    const Vector dx = x_next - summary.x;
    const double step_norm = dx.norm();
    if (step_norm == 0.0) {
      end_on(Termination::kStationary,
             "zero step at iteration " + std::to_string(summary.iterations + 1));
      break;
    }
    if (!finite(loss_next)) {
      std::ostringstream msg;
      msg << where << "the loss at the new point is " << loss_next;
      if (std::isfinite(loss_next)) msg << ", its gradient is not finite";
      end_on(Termination::kNumericalFailure, msg.str());
      break;
    }
    const double loss_before = summary.loss;
    const Vector x_before = summary.x;
    summary.x = x_next;
    summary.loss = loss_next;
    ++summary.iterations;
    stop = record(step_norm);
    done = !stop && (rules.at_point(summary.loss, summary.x, tested_gradient, summary) ||
                     rules.after_step(loss_before, summary.loss, x_before, dx, summary));
  }
  if (stop) {
    end_on(Termination::kStopped,
           "the callback asked to stop after iteration " + std::to_string(summary.iterations));
  } else if (summary.termination == Termination::kMaxIterations) {
    summary.message = "max_iterations = " + std::to_string(options.max_iterations) + " reached";
  } else if (converged(summary.termination) && !(summary.loss <= summary.initial_loss)) {
    end_on(Termination::kDiverged, to_string(summary.termination) + " held (" + summary.message +
                                       "), but L = " + report_number(summary.loss) +
                                       " is above L(x₀) = " + report_number(summary.initial_loss));
  }
  summary.history.assign(std::make_move_iterator(history.begin()),
                         std::make_move_iterator(history.end()));
  summary.counts = simulator.counts() - counts_at_start;
  summary.at_bounds = domain.count_at_bounds(summary.x);
  summary.wall_seconds = seconds_since(start);
  return summary;
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
