#include "physgrad/optim/minimize.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <iterator>
#include <optional>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/text.hpp"
#include "physgrad/timing.hpp"

namespace physgrad {

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

// One run of minimize(): the checked problem, the box, the summary it fills and the records kept.
// Everything reaches the simulator through `problem_`, whose simulator is checked and counted (a
// nested run, pg's local inverse, shares the outer run's CheckedSimulator).
class MinimizeRun {
 public:
  MinimizeRun(Optimizer& optimizer, const Objective& objective, const Vector& x0,
              const MinimizeOptions& options);
  // The loss at x0, the budget and the stopping rules, the first record and the tests at x0.
  void begin();
  // One iteration; false when the run ends (a limit, a stopping rule, a failure, the callback).
  bool iterate();
  // The message of the ending, the history, the counts and the time.
  MinimizeSummary finish();

 private:
  // What the rule proposed and where it leads (x_next empty and loss_next NaN when nowhere).
  struct Trial {
    Step step;
    Vector x_next;
    double loss_next = NAN;
  };
  double evaluate(const Vector& x);
  bool finite(double value) const;
  bool record(double step_norm);
  void end_on(Termination termination, std::string message);
  bool propose(Trial& trial, const std::string& where);
  void take_rejected(const Step& step);
  void take_accepted(const Trial& trial, const std::string& where);
  const Vector* tested_gradient() const { return with_gradient_ ? &gradient_ : nullptr; }

  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  Optimizer& optimizer_;
  const MinimizeOptions& options_;
  const CheckedObjective checked_;
  const Objective& problem_;
  const CheckedSimulator& simulator_;
  const SimulatorCounts counts_at_start_;
  const Domain domain_;
  const bool with_gradient_;  // L and ∇L at every point, for the gradient test
  Vector gradient_;
  MinimizeSummary summary_;
  std::optional<SimulatorBudget> budget_;
  std::optional<StoppingRules> rules_;
  std::size_t kept_;
  std::deque<IterationRecord> history_;  // a deque: dropping the record after the start is O(1)
  bool stopped_ = false, done_ = false;  // the callback asked to stop; a test or failure ended it
};

MinimizeRun::MinimizeRun(Optimizer& optimizer, const Objective& objective, const Vector& x0,
                         const MinimizeOptions& options)
    : optimizer_(optimizer),
      options_(options),
      checked_(objective),
      problem_(checked_.objective()),
      simulator_(checked_.simulator()),
      counts_at_start_(simulator_.counts()),
      domain_(problem_.dim(), options.lower, options.upper, options.x_scale),
      with_gradient_(options.gradient_tolerance > 0) {
  domain_.check_dim(x0.size(), "minimize");
  domain_.check_contains(x0, "minimize: x0");
  summary_.optimizer = optimizer.id();
  summary_.params = optimizer.params();
  summary_.parameters = x0.size();
  summary_.bounded = domain_.bounded();
  summary_.scaled = domain_.scaled();
  summary_.x = x0;
  summary_.termination = Termination::kMaxIterations;
  // The records kept: the start and the latest, within both limits.
  kept_ = static_cast<std::size_t>(std::max<long long>(
      2, std::min(options.max_history,
                  options.max_history_values / std::max<long long>(1, x0.size()))));
}

// L (and ∇L when the gradient test is on) at a point, timed as minimize's own evaluations.
double MinimizeRun::evaluate(const Vector& x) {
  const auto begin = std::chrono::steady_clock::now();
  const double value =
      with_gradient_ ? problem_.value_and_gradient(x, gradient_) : problem_.value(x);
  summary_.evaluation_seconds += seconds_since(begin);
  ++summary_.evaluations;
  return value;
}

// A non-finite ∇L, where the gradient test asks for it, ends a run as a non-finite L does.
bool MinimizeRun::finite(double value) const {
  return std::isfinite(value) && (!with_gradient_ || all_finite(gradient_));
}

// Keeps the record of the current point; true when the callback asks to stop.
bool MinimizeRun::record(double step_norm) {
  if (history_.size() >= kept_) {
    history_.erase(history_.begin() + 1);
    ++summary_.history_dropped;
  }
  history_.push_back({summary_.iterations, summary_.loss, step_norm, seconds_since(start_),
                      summary_.evaluations, simulator_.counts() - counts_at_start_, summary_.x});
  return options_.callback && options_.callback(history_.back());
}

void MinimizeRun::end_on(Termination termination, std::string message) {
  summary_.termination = termination;
  summary_.message = std::move(message);
  done_ = true;
}

void MinimizeRun::begin() {
  summary_.loss = evaluate(summary_.x);
  summary_.initial_loss = summary_.loss;
  if (!std::isfinite(summary_.loss)) {
    std::ostringstream msg;
    msg << "the loss at the starting point is " << summary_.loss;
    throw Error(msg.str());
  }
  // Opened after the start: its evaluation is always made.
  budget_.emplace(simulator_, options_.max_evaluations, options_.max_seconds,
                  counts_at_start_.passes, start_);
  rules_.emplace(options_, domain_, summary_.initial_loss);
  summary_.stopping_rules = rules_->listed();
  optimizer_.reset();
  stopped_ = record(0.0);
  done_ = !stopped_ && rules_->at_point(summary_.loss, summary_.x, tested_gradient(), summary_);
  if (!stopped_ && !done_ && !finite(summary_.loss)) {
    end_on(Termination::kNumericalFailure, "the gradient at the starting point is not finite");
  }
}

// The rule's step and the loss where it leads; false when that ended the run (a numerical
// failure inside the rule, this run's budget).
bool MinimizeRun::propose(Trial& trial, const std::string& where) {
  try {
    const auto step_start = std::chrono::steady_clock::now();
    trial.step = optimizer_.step(problem_, summary_.x, domain_);
    summary_.step_seconds += seconds_since(step_start);
    summary_.evaluations += trial.step.evaluations;
    if (trial.step.status == Step::Status::kOk && all_finite(trial.step.delta)) {
      // The rule keeps x + Δx in the box; the projection only removes rounding in the sum.
      trial.x_next = domain_.project(summary_.x + trial.step.delta);
      if (trial.x_next != summary_.x) trial.loss_next = evaluate(trial.x_next);
    }
  } catch (const NumericalError& e) {
    end_on(Termination::kNumericalFailure, where + e.what());
    return false;
  } catch (const BudgetExhausted& e) {
    if (e.budget() != &*budget_) throw;  // an outer run's budget: that run ends
    const bool passes = e.kind() == BudgetExhausted::Kind::kPasses;
    end_on(passes ? Termination::kMaxEvaluations : Termination::kMaxSeconds,
           std::string(passes ? "max_evaluations" : "max_seconds") + " reached in iteration " +
               std::to_string(summary_.iterations + 1) + ": " + e.what());
    return false;
  }
  return true;
}

// A rejected trial counts as an iteration; one too short to matter ends the run like an
// accepted one (the loss did not move).
void MinimizeRun::take_rejected(const Step& step) {
  ++summary_.iterations;
  ++summary_.rejected_steps;
  stopped_ = record(0.0);
  done_ = !stopped_ && step.delta.size() == summary_.x.size() &&
          rules_->after_step(summary_.loss, summary_.loss, summary_.x, step.delta, summary_, false);
}

// Moves to the trial's point unless its step or loss is not finite or it stays where it is,
// then tests the stopping rules there.
void MinimizeRun::take_accepted(const Trial& trial, const std::string& where) {
  if (!all_finite(trial.step.delta)) {
    return end_on(Termination::kNumericalFailure, where + "non-finite step");
  }
  const Vector dx = trial.x_next - summary_.x;
  const double step_norm = dx.norm();
  if (step_norm == 0.0) {
    return end_on(Termination::kStationary,
                  "zero step at iteration " + std::to_string(summary_.iterations + 1));
  }
  if (!finite(trial.loss_next)) {
    std::ostringstream msg;
    msg << where << "the loss at the new point is " << trial.loss_next;
    if (std::isfinite(trial.loss_next)) msg << ", its gradient is not finite";
    return end_on(Termination::kNumericalFailure, msg.str());
  }
  const double loss_before = summary_.loss;
  const Vector x_before = summary_.x;
  summary_.x = trial.x_next;
  summary_.loss = trial.loss_next;
  ++summary_.iterations;
  stopped_ = record(step_norm);
  done_ = !stopped_ && (rules_->at_point(summary_.loss, summary_.x, tested_gradient(), summary_) ||
                        rules_->after_step(loss_before, summary_.loss, x_before, dx, summary_));
}

bool MinimizeRun::iterate() {
  if (stopped_ || done_ || summary_.iterations >= options_.max_iterations) return false;
  if (budget_->out_of_time()) {
    end_on(Termination::kMaxSeconds, "max_seconds = " + report_number(options_.max_seconds) +
                                         " reached after iteration " +
                                         std::to_string(summary_.iterations));
    return false;
  }
  // Numerical failures name the iteration, the rule and the place.
  const std::string where =
      "iteration " + std::to_string(summary_.iterations + 1) + " of " + optimizer_.id() + ": ";
  Trial trial;
  if (!propose(trial, where)) return false;
  if (trial.step.status == Step::Status::kFailed) {
    end_on(Termination::kFailed, trial.step.message);
  } else if (trial.step.status == Step::Status::kRejected) {
    take_rejected(trial.step);
  } else {
    take_accepted(trial, where);
  }
  return !stopped_ && !done_;
}

MinimizeSummary MinimizeRun::finish() {
  if (stopped_) {
    end_on(Termination::kStopped,
           "the callback asked to stop after iteration " + std::to_string(summary_.iterations));
  } else if (summary_.termination == Termination::kMaxIterations) {
    summary_.message = "max_iterations = " + std::to_string(options_.max_iterations) + " reached";
  } else if (converged(summary_.termination) && !(summary_.loss <= summary_.initial_loss)) {
    end_on(Termination::kDiverged,
           to_string(summary_.termination) + " held (" + summary_.message + "), but L = " +
               report_number(summary_.loss) +
               " is above L(x₀) = " + report_number(summary_.initial_loss));
  }
  summary_.history.assign(std::make_move_iterator(history_.begin()),
                          std::make_move_iterator(history_.end()));
  summary_.counts = simulator_.counts() - counts_at_start_;
  summary_.at_bounds = domain_.count_at_bounds(summary_.x);
  summary_.wall_seconds = seconds_since(start_);
  return std::move(summary_);
}

}  // namespace

MinimizeSummary minimize(Optimizer& optimizer, const Objective& objective, const Vector& x0,
                         const MinimizeOptions& options) {
  check_minimize_options(options);
  MinimizeRun run(optimizer, objective, x0, options);
  run.begin();
  while (run.iterate()) {
  }
  return run.finish();
}

}  // namespace physgrad
