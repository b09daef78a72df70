#include "physgrad/optim/minimize.hpp"

#include <chrono>
#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

std::string to_string(Termination termination) {
  switch (termination) {
    case Termination::kConverged: return "converged";
    case Termination::kMaxIterations: return "max_iterations";
    case Termination::kStationary: return "stationary";
    case Termination::kNumericalFailure: return "numerical_failure";
    case Termination::kFailed: return "failed";
    case Termination::kStopped: return "stopped";
  }
  return "unknown";
}

MinimizeSummary minimize(Optimizer& optimizer, const Objective& objective, const Vector& x0,
                         const MinimizeOptions& options) {
  if (options.max_iterations < 1) {
    throw Error("minimize: max_iterations must be ≥ 1, got " +
                std::to_string(options.max_iterations));
  }
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };

  MinimizeSummary summary;
  summary.x = x0;
  summary.loss = objective.value(x0);
  if (!std::isfinite(summary.loss)) {
    std::ostringstream msg;
    msg << "the loss at the starting point is " << summary.loss;
    throw Error(msg.str());
  }
  int evaluations = 1;
  const auto record = [&](double step_norm) {
    summary.history.push_back(
        {summary.iterations, summary.loss, step_norm, elapsed(), evaluations, summary.x});
    return options.callback && options.callback(summary.history.back());
  };

  optimizer.reset();
  bool stop = record(0.0);
  summary.termination = Termination::kMaxIterations;
  while (!stop) {
    if (summary.loss <= options.loss_tolerance) {
      summary.termination = Termination::kConverged;
      break;
    }
    if (summary.iterations >= options.max_iterations) break;

    // Numerical failures name the iteration, the rule and the place.
    const std::string where =
        "iteration " + std::to_string(summary.iterations + 1) + " of " + optimizer.id() + ": ";
    Step step;
    try {
      step = optimizer.step(objective, summary.x);
    } catch (const NumericalError& e) {
      summary.termination = Termination::kNumericalFailure;
      summary.message = where + e.what();
      break;
    }
    evaluations += step.evaluations;
    if (step.status == Step::Status::kFailed) {
      summary.termination = Termination::kFailed;
      summary.message = step.message;
      break;
    }
    if (step.status == Step::Status::kRejected) {
      ++summary.iterations;
      stop = record(0.0);
      continue;
    }
    if (!all_finite(step.dx)) {
      summary.termination = Termination::kNumericalFailure;
      summary.message = where + "non-finite step";
      break;
    }
    const double step_norm = step.dx.norm();
    if (step_norm == 0.0) {
      summary.termination = Termination::kStationary;
      summary.message = "zero step at iteration " + std::to_string(summary.iterations + 1);
      break;
    }
    const Vector x_next = summary.x + step.dx;
    const double loss_next = objective.value(x_next);
    ++evaluations;
    if (!std::isfinite(loss_next)) {
      summary.termination = Termination::kNumericalFailure;
      std::ostringstream msg;
      msg << where << "the loss at the new point is " << loss_next;
      summary.message = msg.str();
      break;
    }
    summary.x = x_next;
    summary.loss = loss_next;
    ++summary.iterations;
    stop = record(step_norm);
  }
  if (stop) summary.termination = Termination::kStopped;
  summary.wall_seconds = elapsed();
  return summary;
}

}  // namespace physgrad
