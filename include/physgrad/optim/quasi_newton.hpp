// QuasiNewton — the step shared by BFGS and L-BFGS: Δx = α p with p = −H ∇L from the rule's
// curvature model H and α from a strong-Wolfe line search; then the pair (s = Δx, y = Δ∇L) updates H.
#pragma once

#include <vector>

#include "physgrad/optim/line_search.hpp"
#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

// A pair with yᵀs ≤ 1e-10·‖s‖‖y‖ carries no usable curvature and is skipped. When the line
// search along p fails, the curvature model is dropped and the search is retried once along
// −∇L (unless p already was −∇L); if that fails as well the step reports kFailed with the
// line-search message.
//
// The first trial step is initial_step; along −∇L without curvature information (the first step
// of a run, restarts) it is initial_step·min(1, 1/‖∇L‖) instead, so that trial moves x by at most
// initial_step (−∇L has no natural length, N&W §3.5).
//
// The gradient at the point a step moved to is reused by the next step when that step starts
// exactly there; any other x is evaluated afresh. The cache assumes one objective per run.
//
// In the domain: the model works in z = x ⊘ s (pairs D⁻¹s and D y, first trial length in z).
// With bounds, the variables held at a bound (Domain::free_variables) and free ones at a bound
// that p would push outward get pᵢ = 0 (p stays a descent direction), and the line search is
// bounded by the step where the ray x + αDp leaves the box (it accepts that step when φ still
// decreases there).
// The option "initial_step" of bfgs and lbfgs, the first trial α₀ of every line search; settings
// may also give it as "lr", the step size of the other rules.
template <class Options>
RuleOption<Options> initial_step_option(double Options::*member) {
  RuleOption<Options> option = rule_option("initial_step", member, positive(),
                                           "first trial step α₀ of every line search");
  option.alias = "lr";
  return option;
}

class QuasiNewton : public Optimizer {
 public:
  void reset() override;

 protected:
  // Throws Error naming the field when initial_step or the line-search options are out of range.
  QuasiNewton(double initial_step, const LineSearchOptions& line_search);

  virtual Vector direction(const Vector& gradient) const = 0;  // p = −H ∇L
  virtual bool has_curvature() const = 0;                       // false while H is the identity
  virtual void clear_curvature() = 0;
  // Called with pairs that pass the curvature test only (yᵀs > 0).
  virtual void add_pair(const Vector& s, const Vector& y) = 0;

 private:
  Step propose(const Objective& objective, const Vector& x, const Domain& domain) final;
  LineSearchResult search(const Objective& objective, const Vector& x, const Vector& pz,
                          const Domain& domain) const;

  double initial_step_;
  LineSearchOptions line_search_;
  Vector x_;  // point of the cached value_ and g_ (empty: no cache)
  double value_ = 0;
  Vector g_;
};

}  // namespace physgrad
