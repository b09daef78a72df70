#include "physgrad/optim/local_inverse.hpp"

#include <cmath>
#include <memory>
#include <optional>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/optim/inverse_gradient.hpp"
#include "physgrad/optim/lbfgs.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/spectral_cut.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

namespace {

constexpr NameTable<InverseMethod, 5> kMethodNames{{
    {InverseMethod::kAuto, "auto"},
    {InverseMethod::kAnalytic, "analytic"},
    {InverseMethod::kTimeReversal, "time_reversal"},
    {InverseMethod::kLbfgs, "lbfgs"},
    {InverseMethod::kInverseGradient, "ig"},
}};

// Throws NumericalError "WHO: WHAT has a non-finite entry at index I (nan)" unless every entry
// of v is finite.
void require_finite_inverse_entries(const Vector& v, const std::string& who, const char* what) {
  for (Index i = 0; i < v.size(); ++i) {
    if (std::isfinite(v(i))) continue;
    std::ostringstream msg;
    msg << who << ": " << what << " has a non-finite entry at index " << i << " (" << v(i) << ")";
    throw NumericalError(msg.str());
  }
}

// The tolerance every method is judged by: ‖P(x) − y‖ ≤ tolerance·(1 + ‖y‖), or
// ≤ relative_tolerance·‖P(x₀) − y‖ (`start`, asked only when the first test fails). A NaN
// residual meets neither.
template <class StartResidual>
bool meets_inverse_tolerance(double residual, const Vector& y, const LocalInverseOptions& options,
                             StartResidual start) {
  if (residual <= options.tolerance * (1 + y.norm())) return true;
  return options.relative_tolerance > 0 && residual <= options.relative_tolerance * start();
}

// The simulator's own inverse or its anchored time reversal, projected onto the box, judged by
// the tolerances.
LocalInverseResult closed_form(const Simulator& simulator, InverseMethod method, const Vector& y,
                               const Vector& x0, const Vector& context,
                               const LocalInverseOptions& options, const Domain& domain) {
  LocalInverseResult result;
  const std::string who = "local inverse (" + to_string(method) + ")";
  std::optional<Vector> y0;  // P(x₀), when computed
  if (method == InverseMethod::kAnalytic) {
    if (!simulator.has_inverse()) {
      throw Error("simulator '" + simulator.name() +
                  "' has no analytic inverse; use a numerical one (lbfgs or ig)");
    }
    result.x = simulator.inverse(y, x0, context);
    result.evaluations = 2;
  } else {
    if (!simulator.has_time_reversal()) {
      throw Error("simulator '" + simulator.name() +
                  "' has no time reversal; use a numerical inverse (lbfgs or ig)");
    }
    // x₀ + R(y) − R(P(x₀)): maps P(x₀) to x₀ exactly, so the reversal's own error (the
    // truncation error of a scheme that is not reversible) cancels to first order near x₀.
    y0 = simulator.forward(x0, context);
    result.x = x0 + (simulator.time_reversal(y, context) - simulator.time_reversal(*y0, context));
    result.evaluations = 4;
  }
  // Named as the caller asked for it (auto, say), then as it ran.
  require_finite_inverse_entries(
      result.x, "the local inverse (" + to_string(options.method) + ") gave no finite preimage",
      method == InverseMethod::kAnalytic ? "the simulator's inverse (analytic)"
                                         : "the anchored reversal (time_reversal)");
  result.x = domain.project(result.x);
  result.residual = (simulator.forward(result.x, context) - y).norm();
  if (!std::isfinite(result.residual)) {
    throw NumericalError(who + ": P(x) at the preimage is not finite");
  }
  result.converged = meets_inverse_tolerance(result.residual, y, options, [&] {
    if (!y0) {  // the analytic inverse: one more forward pass, only for this test
      y0 = simulator.forward(x0, context);
      ++result.evaluations;
    }
    return (*y0 - y).norm();
  });
  return result;
}

// The minimizer of ½‖P(x) − y‖² from x₀ by L-BFGS or full inverse-gradient steps.
LocalInverseResult numerical(const Simulator& simulator, InverseMethod method, const Vector& y,
                             const Vector& x0, const Vector& context,
                             const LocalInverseOptions& options, const Domain& domain) {
  const L2Loss half_squares;
  const Objective misfit(simulator, half_squares, y, context);
  LocalInverseResult result;
  const double start = misfit.value(x0);
  result.evaluations = 1;
  if (!std::isfinite(start)) {
    throw NumericalError("local inverse (" + to_string(method) + "): P(x0) is not finite");
  }
  std::unique_ptr<Optimizer> solver;
  if (method == InverseMethod::kLbfgs) {
    solver = std::make_unique<Lbfgs>();
  } else {  // the full inverse-gradient step J⁺(y − P(x)) on ½‖P(x) − y‖²
    solver = std::make_unique<InverseGradient>(InverseGradientOptions{1.0, options.rcond});
  }
  // ‖r‖ ≤ a ⟺ ½‖r‖² ≤ ½a², and ‖r‖ ≤ ρ‖r₀‖ ⟺ ½‖r‖² ≤ ρ²·½‖r₀‖².
  const double absolute = options.tolerance * (1 + y.norm());
  MinimizeOptions run;
  run.max_iterations = options.max_iterations;
  run.loss_tolerance = 0.5 * absolute * absolute;
  run.relative_loss_tolerance = options.relative_tolerance * options.relative_tolerance;
  run.function_tolerance = options.function_tolerance;
  const Index n = x0.size();
  if (domain.bounded()) {
    run.lower = domain.lower(n);
    run.upper = domain.upper(n);
  }
  if (domain.scaled()) run.x_scale = domain.scale(n);
  const MinimizeSummary summary = minimize(*solver, misfit, x0, run);
  if (summary.termination == Termination::kNumericalFailure) {
    throw NumericalError("local inverse (" + to_string(method) + "): " + summary.message);
  }
  result.x = summary.x;
  result.residual = std::sqrt(2 * summary.loss);
  result.iterations = summary.iterations;
  result.evaluations = 1 + summary.evaluations;
  // Judged by the residual, not by why minimize() stopped: a stall (function_tolerance) or the
  // iteration budget leaves it unconverged.
  result.converged = meets_inverse_tolerance(result.residual, y, options,
                                             [start] { return std::sqrt(2 * start); });
  return result;
}

}  // namespace

std::string to_string(InverseMethod method) {
  return name_of(kMethodNames, method, "InverseMethod");
}

InverseMethod parse_inverse_method(const std::string& text) {
  return value_named(kMethodNames, text, "inverse method");
}

const OptionList<LocalInverseOptions>& LocalInverseOptions::descriptors() {
  using O = LocalInverseOptions;
  static const OptionList<O> options = [] {
    OptionList<O> list = {
        rule_option("inverse", &O::method,
                    {InverseMethod::kAuto, InverseMethod::kAnalytic, InverseMethod::kTimeReversal,
                     InverseMethod::kLbfgs, InverseMethod::kInverseGradient},
                    "the local inverse P⁻¹"),
        rule_option("inverse_tolerance", &O::tolerance, positive(),
                    "stop once ‖P(x) − y‖ ≤ tolerance·(1 + ‖y‖)"),
        rule_option("inverse_relative_tolerance", &O::relative_tolerance, fraction(),
                    "... or once ‖P(x) − y‖ ≤ this·‖P(x₀) − y‖ (0: off)"),
        rule_option("inverse_function_tolerance", &O::function_tolerance, non_negative(),
                    "... or once a step changes ½‖P(x) − y‖² by ≤ this·its value (0: off)"),
        rule_option("inverse_iterations", &O::max_iterations, integer_at_least(1),
                    "iterations of the numerical inverse at most"),
        rule_option("inverse_rcond", &O::rcond, rcond_option_description().range,
                    "ig: " + rcond_option_description().help),
    };
    // The numerical methods' settings mean nothing for the analytic and time-reversal inverses.
    for (RuleOption<O>& option : list) {
      if (option.name == "inverse") continue;
      option.applies = [](const O& o) {
        return o.method != InverseMethod::kAnalytic && o.method != InverseMethod::kTimeReversal;
      };
    }
    return list;
  }();
  return options;
}

LocalInverseResult local_inverse(const Simulator& user_simulator, const Vector& y,
                                 const Vector& x0, const Vector& context,
                                 const LocalInverseOptions& options, const Domain& domain) {
  // Every call below goes through a checked, counted simulator: pg's own, or one of this solve.
  std::optional<CheckedSimulator> local;
  const CheckedSimulator& simulator = CheckedSimulator::around(user_simulator, local);
  const SimulatorCounts counts_at_start = simulator.counts();
  std::ostringstream msg;
  if (y.size() != simulator.output_dim()) {
    msg << "local inverse: y has " << y.size() << " entries, simulator '" << simulator.name()
        << "' has output_dim " << simulator.output_dim();
  } else if (x0.size() != simulator.input_dim()) {
    msg << "local inverse: x0 has " << x0.size() << " entries, simulator '" << simulator.name()
        << "' has input_dim " << simulator.input_dim();
  } else if (context.size() != 0 && context.size() != simulator.context_dim()) {
    msg << "local inverse: context has " << context.size() << " entries, simulator '"
        << simulator.name() << "' expects " << simulator.context_dim();
  }
  if (!msg.str().empty()) throw Error(msg.str());
  domain.check_dim(x0.size(), "local inverse");
  check_options("local inverse", options);
  require_finite_inverse_entries(y, "local inverse", "y");
  require_finite_inverse_entries(x0, "local inverse", "x0");
  InverseMethod method = options.method;
  if (method == InverseMethod::kAuto) {
    method = simulator.has_inverse()         ? InverseMethod::kAnalytic
             : simulator.has_time_reversal() ? InverseMethod::kTimeReversal
                                             : InverseMethod::kLbfgs;
  }
  LocalInverseResult result;
  if (method == InverseMethod::kAnalytic || method == InverseMethod::kTimeReversal) {
    result = closed_form(simulator, method, y, x0, context, options, domain);
  } else {
    result = numerical(simulator, method, y, x0, context, options, domain);
  }
  result.counts = simulator.counts() - counts_at_start;
  return result;
}

}  // namespace physgrad
