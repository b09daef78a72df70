// Optimizer — one update rule for direct optimization: given x, propose Δx.
// Per-run state (moments, curvature pairs, damping) lives in the object; reset() clears it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "physgrad/optim/domain.hpp"
#include "physgrad/optim/objective.hpp"
#include "physgrad/rule_step.hpp"

namespace physgrad {

class Optimizer {
 public:
  virtual ~Optimizer() = default;
  // Short lower-case id: gd, momentum, adam, newton, bfgs, lbfgs, gn, lm, ig, pg.
  virtual std::string id() const = 0;
  // Every setting that distinguishes a run (lr, beta, ...), for config and summary files.
  virtual nlohmann::json params() const = 0;
  // Forget per-run state; called by minimize() before the first step.
  virtual void reset() {}
  // Proposes Δx at x, which lies in `domain`'s box; x + Δx lies in it too (up to rounding in the
  // sum: minimize() clamps the new iterate). The default domain is unbounded with unit scale.
  // The rule sees the objective's simulator through a CheckedSimulator (the one minimize() puts
  // around it, or one of its own). Throws Error when x or the domain has another dimension than
  // the objective, or the rule returns a delta of another size (an empty delta is allowed for a
  // rejected trial or a failure).
  Step step(const Objective& objective, const Vector& x, const Domain& domain = {});

 private:
  // The rule's update: in the scaled variables z = x ⊘ s, and what it does with bounds.
  virtual Step propose(const Objective& objective, const Vector& x, const Domain& domain) = 0;
};

// Throws Error naming `what` unless value is finite and > 0.
void require_positive(const char* what, double value);
// Throws Error naming `what` unless value is finite and lo ≤ value < hi.
void require_in_range(const char* what, double value, double lo, double hi);

}  // namespace physgrad
