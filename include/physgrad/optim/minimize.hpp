// minimize — runs an Optimizer on an Objective: x_{k+1} = Π(x_k + Δx_k) (Π the projection onto
// the box bounds) until a stopping rule holds, the budget runs out, or a step fails.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "physgrad/optim/optimizer.hpp"
#include "physgrad/physics/checked_simulator.hpp"

namespace physgrad {

// Why a run ended. The first five are convergence (converged() is true for them); the stopping
// rules are tested at the start and after every step that moved x, in this order.
enum class Termination {
  kConverged,           // L(x) ≤ loss_tolerance
  kRelativeLoss,        // L(x) ≤ relative_loss_tolerance·L(x₀)
  kGradientTolerance,   // the projected gradient is at most gradient_tolerance
  kFunctionTolerance,   // the last step changed L by at most function_tolerance·L
  kParameterTolerance,  // the last step was at most parameter_tolerance·(‖x‖ + parameter_tolerance)
  kDiverged,            // a stopping rule held, but L(x) is above L(x₀): a run that made the
                        // loss worse never counts as converged (the message names the rule)
  kMaxIterations,       // the iteration budget ran out
  kMaxEvaluations,      // the budget of simulator passes ran out (max_evaluations)
  kMaxSeconds,          // the time budget ran out (max_seconds)
  kStationary,          // the rule proposed a zero step (gradient zero, nothing to do)
  kNumericalFailure,    // Δx or L(x + Δx) was NaN/Inf, or the rule met a NumericalError; x keeps
                        // its last finite value
  kFailed,              // the rule reported that it cannot continue
  kStopped,             // the callback asked to stop
};
// "converged", "relative_loss", "gradient_tolerance", "function_tolerance",
// "parameter_tolerance", "diverged", "max_iterations", "max_evaluations", "max_seconds",
// "stationary", "numerical_failure", "failed", "stopped".
std::string to_string(Termination termination);
// True for the five stopping rules (the run reached what was asked of it).
bool converged(Termination termination);

struct IterationRecord {
  int iteration = 0;  // 0 is the starting point
  double loss = 0;
  double step_norm = 0;  // ‖Δx‖ of the step that led here
  double seconds = 0;    // wall time since the start of minimize()
  int evaluations = 0;   // cumulative objective evaluations
  SimulatorCounts counts;  // cumulative simulator work (the rule's inner solves included)
  Vector x;
};

// The stopping rules follow Ceres' Solver::Options; each is off at its default 0 (Ceres'
// defaults would be function 1e-6, gradient 1e-10, parameter 1e-8). Norms are taken in the
// scaled variables z = x ⊘ s when x_scale is set (s = 1 otherwise). Every test is NaN-safe: a
// NaN or infinite quantity never satisfies it.
struct MinimizeOptions {
  int max_iterations = 100;  // ≥ 1
  // Absolute: stop once L(x) ≤ loss_tolerance (Termination::kConverged); ≥ 0.
  double loss_tolerance = 0.0;
  // Called after every iteration (and for the start); return true to stop the run.
  std::function<bool(const IterationRecord&)> callback = nullptr;
  // Relative to the start: stop once L(x) ≤ relative_loss_tolerance·L(x₀) (kRelativeLoss);
  // in [0, 1).
  double relative_loss_tolerance = 0.0;
  // Stop once ‖(x − Π(x − D²∇L(x))) ⊘ s‖∞ ≤ gradient_tolerance (kGradientTolerance): the max
  // norm of the projected gradient, ‖∇L‖∞ without bounds and scale. Costs one gradient per
  // iteration (L and ∇L are then evaluated together). ≥ 0.
  double gradient_tolerance = 0.0;
  // After a step from x to x₊: stop once |L(x) − L(x₊)| ≤ function_tolerance·L(x)
  // (kFunctionTolerance). Rejected trials (lm) move nothing and are not tested. ≥ 0.
  double function_tolerance = 0.0;
  // After a step Δx from x: stop once ‖Δx ⊘ s‖₂ ≤ parameter_tolerance·(‖x ⊘ s‖₂ +
  // parameter_tolerance) (kParameterTolerance); also tested on a rejected trial (lm), as in
  // Ceres. ≥ 0.
  double parameter_tolerance = 0.0;
  // Box bounds lower ≤ x ≤ upper: n entries each or empty (unbounded; ±inf entries leave one
  // side open). x0 must lie inside. Every rule keeps its iterates inside (docs/update_rules.md).
  Vector lower = Vector();
  Vector upper = Vector();
  // The characteristic size sᵢ > 0 of each variable (n entries, or empty for 1): the rules work
  // in z = x ⊘ s (scipy's x_scale). Choose sᵢ about the size of the change xᵢ needs.
  Vector x_scale = Vector();
  // Budgets, each off at 0. max_evaluations bounds the run's simulator passes
  // (SimulatorCounts::passes: forward and VJP samples, m per Jacobian, 2n per weighted Hessian,
  // 1 per time reversal or inverse), the work of the rule's inner solves (pg's numerical local
  // inverse) included: the evaluation of x₀ is always made, after it no simulator call is made
  // that would take the passes beyond the budget (kMaxEvaluations). max_seconds bounds the wall
  // time: no simulator call starts, and no iteration, once it has passed (kMaxSeconds). A run
  // ended by a budget keeps its last accepted x. ≥ 0.
  long long max_evaluations = 0;
  double max_seconds = 0.0;
  // The history kept (MinimizeSummary::history): the start and the latest records, at most
  // max_history of them and at most max_history_values entries of x in all (for n parameters,
  // max(2, max_history_values / n) records), so that its memory is bounded whatever the run's
  // length and dimension; the records in between are dropped (history_dropped counts them).
  // Each ≥ 2; the defaults keep 10⁵ records, fewer for n > 100 (80 MB of x at most).
  long long max_history = 100000;
  long long max_history_values = 10000000;
};

struct MinimizeSummary {
  Termination termination = Termination::kMaxIterations;
  std::string message;                   // why it ended, with the numbers of the test that held
  std::vector<IterationRecord> history;  // history[0] is the start, then the latest records
  long long history_dropped = 0;         // records dropped between them (max_history)
  Vector x;                              // last finite iterate
  double loss = 0;                       // L(x)
  double initial_loss = 0;               // L(x₀)
  int iterations = 0;                    // accepted updates made (rejected trials count too)
  int rejected_steps = 0;                // of those, trials the rule rejected (x stayed)
  int evaluations = 0;                   // objective evaluations (rule's and minimize's)
  SimulatorCounts counts;                // the simulator's work in the run (inner solves included)
  double wall_seconds = 0;
  double step_seconds = 0;        // time inside the rule's step()
  double evaluation_seconds = 0;  // time of minimize's own evaluations of L (and ∇L)
  // What ran: the rule, its parameters, the dimension, the box and scale, the stopping rules.
  std::string optimizer;
  nlohmann::json params;
  Index parameters = 0;
  bool bounded = false;
  bool scaled = false;
  Index at_bounds = 0;  // variables of x at one of their bounds
  double gradient_norm = -1;  // the last projected-gradient norm tested (-1: not computed)
  std::vector<std::pair<std::string, double>> stopping_rules;  // name, value (those set, and
                                                               // the budgets set)
};

// The rule sees the objective's simulator through a CheckedSimulator (the sizes of its results
// checked, its work counted and budgeted); an Error or an exception of the simulator's own
// propagates, a NumericalError ends the run with kNumericalFailure.
MinimizeSummary minimize(Optimizer& optimizer, const Objective& objective, const Vector& x0,
                         const MinimizeOptions& options = {});

// One line: "lbfgs: 34 iterations, 71 evaluations, 142 simulator passes, loss 1.2e+03 → 4.5e-02,
// gradient_tolerance".
std::string brief_report(const MinimizeSummary& summary);
// A multi-line report in the manner of Ceres' FullReport: the problem (parameters, bounds,
// scale), the rule and its options, the stopping rules and budgets, initial/final/change of the
// loss, iterations (rejected trials), evaluations, the simulator's work by kind, times, and the
// termination with its reason.
std::string full_report(const MinimizeSummary& summary);

}  // namespace physgrad
