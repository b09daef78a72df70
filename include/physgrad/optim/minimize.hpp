// minimize — runs an Optimizer on an Objective: x_{k+1} = x_k + Δx_k until the loss is at
// most loss_tolerance, max_iterations steps were made, or the step becomes non-finite.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

enum class Termination {
  kConverged,         // loss ≤ loss_tolerance
  kMaxIterations,     // the iteration budget ran out
  kStationary,        // the rule proposed a zero step (gradient zero, nothing to do)
  kNumericalFailure,  // Δx or L(x + Δx) was NaN/Inf, or the rule met a NumericalError; x keeps
                      // its last finite value
  kFailed,            // the rule reported that it cannot continue
  kStopped,           // the callback asked to stop
};
std::string to_string(Termination termination);

struct IterationRecord {
  int iteration = 0;  // 0 is the starting point
  double loss = 0;
  double step_norm = 0;  // ‖Δx‖ of the step that led here
  double seconds = 0;    // wall time since the start of minimize()
  int evaluations = 0;   // cumulative objective evaluations
  Vector x;
};

struct MinimizeOptions {
  int max_iterations = 100;              // ≥ 1
  double loss_tolerance = 0.0;           // stop once L(x) ≤ loss_tolerance
  // Called after every iteration (and for the start); return true to stop the run.
  std::function<bool(const IterationRecord&)> callback = nullptr;
};

struct MinimizeSummary {
  Termination termination = Termination::kMaxIterations;
  std::string message;
  std::vector<IterationRecord> history;  // history[0] is the start
  Vector x;                              // last finite iterate
  double loss = 0;                       // L(x)
  int iterations = 0;                    // accepted updates made (rejected trials count too)
  double wall_seconds = 0;
};

MinimizeSummary minimize(Optimizer& optimizer, const Objective& objective, const Vector& x0,
                         const MinimizeOptions& options = {});

}  // namespace physgrad
