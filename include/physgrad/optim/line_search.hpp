// Strong-Wolfe line search — a step α > 0 along a descent direction p, φ(α) = L(x + αp), with
// φ(α) ≤ φ(0) + c1·α·φ'(0) and |φ'(α)| ≤ c2·|φ'(0)| (Nocedal & Wright, Algorithms 3.5 and 3.6).
#pragma once

#include <cmath>
#include <string>

#include "physgrad/optim/objective.hpp"
#include "physgrad/rule_option.hpp"

namespace physgrad {

struct LineSearchOptions {
  // Sufficient decrease (Armijo):   φ(α) ≤ φ(0) + c1·α·φ'(0).
  double c1 = 1e-4;
  // Curvature (strong Wolfe):       |φ'(α)| ≤ c2·|φ'(0)|.
  // Requires 0 < c1 < c2 < 1; a small c2 (0.1) makes the search nearly exact.
  double c2 = 0.9;
  // Trial steps before giving up, ≥ 1; each costs one value-and-gradient evaluation.
  int max_evaluations = 25;
  // Upper bound on α, > 0; the search fails if φ still decreases steeply there.
  double max_step = 1e20;

  // Throws Error naming the field unless 0 < c1 < c2 < 1, max_evaluations ≥ 1, max_step > 0.
  void validate() const;

  // c1 and c2, options of the rules with a line search (bfgs, lbfgs); max_evaluations and
  // max_step are not set by name.
  static const OptionList<LineSearchOptions>& descriptors();
};

struct LineSearchResult {
  bool success = false;  // step satisfies both strong-Wolfe inequalities
  double step = 0;       // α
  double value = 0;      // φ(α) = L(x + αp)
  Vector gradient;       // ∇L(x + αp)
  int evaluations = 0;   // value-and-gradient evaluations spent
  int non_finite = 0;    // of them, those whose value or gradient was not finite
  std::string message;   // why, when !success
};

// Finds α along `direction` from x, given value0 = L(x) and gradient0 = ∇L(x). The first trial
// is α = min(initial_step, max_step, step_limit); while the trials keep satisfying sufficient
// decrease and descending, α grows (cubic extrapolation kept within [1.1α, 10α]); once a bracket is found it is
// narrowed by cubic interpolation, with bisection whenever the interpolant is non-finite or
// outside the middle 80% of the bracket. A trial with a non-finite value or gradient counts as
// too long: it closes the bracket from above and is never accepted.
//
// Failure (success = false, message says why): φ'(0) = gradient0ᵀp is not negative (not a
// descent direction) or value0 is not finite; max_evaluations trials without an acceptable one;
// α reached max_step with φ still decreasing steeply; the bracket shrank below the spacing of
// doubles. step, value and gradient then describe the evaluated trial of lowest φ among those
// with a finite value and gradient that satisfy sufficient decrease, or are 0, value0 and
// gradient0 when there is none.
//
// A bounded search: no trial goes beyond step_limit (where the ray x + αp leaves a feasible
// box, Domain::max_step). A trial at step_limit that satisfies sufficient decrease while φ still
// decreases is accepted (success) without the curvature condition: it is the lowest φ on the
// feasible part of the ray as far as the search can tell.
//
// Throws Error when x, gradient0 or direction do not have objective.dim() entries, when
// initial_step is not finite and > 0, when step_limit is not > 0, or when options are invalid.
LineSearchResult strong_wolfe_line_search(const Objective& objective, const Vector& x,
                                          double value0, const Vector& gradient0,
                                          const Vector& direction, double initial_step,
                                          const LineSearchOptions& options,
                                          double step_limit = INFINITY);

}  // namespace physgrad
