// Local inverse P⁻¹(y; x₀): the simulator's own inverse, its time reversal anchored at x₀
// (x₀ + R(y) − R(P(x₀))), or the minimizer of ½‖P(x; c) − y‖² reached from x₀ by descent.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "physgrad/optim/domain.hpp"
#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

enum class InverseMethod {
  kAuto,          // analytic when the simulator has one, else its time reversal, else L-BFGS
  kAnalytic,      // the simulator's own inverse()
  kTimeReversal,  // the simulator's time_reversal(), anchored at x₀
  kLbfgs,         // L-BFGS with a strong-Wolfe line search
  kInverseGradient,  // full inverse-gradient steps Δx = J⁺(y − P(x)) (optim/inverse_gradient.hpp)
};
std::string to_string(InverseMethod method);
// "auto", "analytic", "time_reversal", "lbfgs" or "ig"; throws unknown_name_error (text.hpp)
// otherwise.
InverseMethod parse_inverse_method(const std::string& text);

// The options of the numerical inverses (lbfgs, ig). The analytic and time-reversal inverses
// take none, but their result is judged by the same tolerance and relative_tolerance (which
// then change no result, and which params() therefore lists for the numerical methods only).
// The member initialisers are the defaults (the rule catalogue's, for pg and sip).
struct LocalInverseOptions {
  InverseMethod method = InverseMethod::kAuto;
  // Stop once ‖P(x) − y‖ ≤ tolerance·(1 + ‖y‖) (absolute), > 0.
  double tolerance = 1e-10;
  int max_iterations = 200;  // ≥ 1
  // ... or once ‖P(x) − y‖ ≤ relative_tolerance·‖P(x₀) − y‖ (relative to the start residual, so
  // a PG step of size Δy is solved to that fraction of Δy), in [0, 1); 0 disables.
  double relative_tolerance = 1e-8;
  // ... or once an iteration changes ½‖P(x) − y‖² by at most function_tolerance times its value
  // (the solve stalls: y is out of reach, or the rest of the misfit is below what rounding lets
  // the steps resolve), ≥ 0; 0 disables. Ceres' default.
  double function_tolerance = 1e-6;
  // ig: singular values σ ≤ rcond·σ_max of J are dropped from its pseudo-inverse, in [0, 1).
  double rcond = 1e-10;

  // Each option once, under the names pg and sip report and take (params(), settings by name,
  // validation): "inverse", and for a numerical method inverse_tolerance, inverse_iterations,
  // inverse_relative_tolerance, inverse_function_tolerance and inverse_rcond.
  static const OptionList<LocalInverseOptions>& descriptors();
};

struct LocalInverseResult {
  Vector x;
  double residual = 0;  // ‖P(x) − y‖
  int iterations = 0;
  // Simulator evaluations spent: forward (+ VJP) passes of the numerical inverse; for the
  // closed forms the inverse or reversals and the forward pass of the residual (and, for the
  // analytic inverse, one at x₀ when the relative test is needed).
  int evaluations = 0;
  SimulatorCounts counts;  // the simulator's work in this solve (CheckedSimulator)
  // ‖P(x) − y‖ ≤ tolerance·(1 + ‖y‖) or ≤ relative_tolerance·‖P(x₀) − y‖, for every method:
  // an inverse that is off, a result projected onto the box or a numerical solve that stalled
  // or ran out of iterations short of both is not converged.
  bool converged = false;
};

// The preimage of y from x₀, inside `domain`: the numerical inverses minimize over the box (in
// the domain's scaled variables); the analytic and time-reversal results are projected onto it.
// x is always finite: a non-finite entry in y or x₀, a non-finite P(x₀) (numerical methods),
// preimage or P(x) at it (closed forms), or numerical trouble inside the numerical inverse (a
// non-finite Jacobian, say) throws NumericalError naming it, for the caller's numerical guard.
// kAnalytic and kTimeReversal throw Error when the simulator lacks them. Throws Error on
// out-of-range options or mismatched sizes, also of what the simulator returns: it is called
// through a CheckedSimulator (that of the calling run, whose counts and budget then include
// this solve, or one of its own).
LocalInverseResult local_inverse(const Simulator& simulator, const Vector& y, const Vector& x0,
                                 const Vector& context, const LocalInverseOptions& options,
                                 const Domain& domain = {});

}  // namespace physgrad
