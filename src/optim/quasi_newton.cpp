#include "physgrad/optim/quasi_newton.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {
// A curvature pair is used only when yᵀs > kCurvatureTolerance·‖s‖‖y‖.
constexpr double kCurvatureTolerance = 1e-10;

// Zeroes the components of a z-direction that may not move: the held variables (`free`), and
// free ones at a bound that p would push out of the box (held along −p). For those gᵢ pᵢ ≥ 0,
// so dropping them keeps p a descent direction. Scaling keeps signs, so z and x agree.
Vector restrict(const Domain& domain, const Vector& x, const std::vector<bool>& free, Vector p) {
  if (!domain.bounded()) return p;
  const std::vector<bool> movable = domain.free_variables(x, -p);
  for (Index i = 0; i < p.size(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (!free[k] || !movable[k]) p(i) = 0;
  }
  return p;
}
}  // namespace

QuasiNewton::QuasiNewton(double initial_step, const LineSearchOptions& line_search)
    : initial_step_(initial_step), line_search_(line_search) {
  line_search_.validate();
}

void QuasiNewton::reset() {
  clear_curvature();
  x_.resize(0);
  g_.resize(0);
}

LineSearchResult QuasiNewton::search(const Objective& objective, const Vector& x,
                                     const Vector& pz, const Domain& domain) const {
  const Vector s = domain.scale(x.size());
  const Vector p = s.cwiseProduct(pz);  // the direction in x
  const double first = has_curvature() ? initial_step_
                                       : initial_step_ * std::min(1.0, 1 / pz.stableNorm());
  if (!(first > 0 && std::isfinite(first))) {
    std::ostringstream msg;
    msg << "line search: the first trial step along a direction of norm " << pz.stableNorm()
        << " is " << first;
    throw NumericalError(msg.str());
  }
  return strong_wolfe_line_search(objective, x, value_, g_, p, first, line_search_,
                                  domain.max_step(x, p));
}

Step QuasiNewton::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  Step out;
  const Index n = x.size();
  if (!(x_.size() == n && x == x_)) {
    if (x_.size() != n) clear_curvature();
    value_ = objective.value_and_gradient(x, g_);
    x_ = x;
    ++out.evaluations;
  }
  if (!all_finite(g_)) throw NumericalError("the gradient at x is not finite");
  // Everything below is in z = x ⊘ s: gradient D g, pairs (D⁻¹s, D y), direction p_z.
  const Vector scale = domain.scale(n);
  const std::vector<bool> free = domain.free_variables(x, g_);
  Vector gz = scale.cwiseProduct(g_);
  for (Index i = 0; i < n; ++i) {
    if (!free[static_cast<std::size_t>(i)]) gz(i) = 0;
  }
  if ((gz.array() == 0).all()) {  // stationary (on the box): a zero step ends the run
    out.delta = Vector::Zero(n);
    return out;
  }

  Vector pz = restrict(domain, x, free, direction(gz));
  LineSearchResult result = search(objective, x, pz, domain);
  out.evaluations += result.evaluations;
  if (!result.success && has_curvature()) {
    out.message = id() + ": restarted along −∇L after: " + result.message;
    clear_curvature();
    pz = restrict(domain, x, free, -gz);
    result = search(objective, x, pz, domain);
    out.evaluations += result.evaluations;
  }
  // A search that failed where the loss or gradient was not finite met numbers, not a hard
  // function: a numerical failure.
  if (!result.success && result.non_finite > 0) {
    const std::string count = result.non_finite == result.evaluations
                                  ? "all " + std::to_string(result.evaluations)
                                  : std::to_string(result.non_finite) + " of " +
                                        std::to_string(result.evaluations);
    throw NumericalError("line search: " + count +
                         " trial points gave a non-finite loss or gradient");
  }
  if (!result.success) {
    out.status = Step::Status::kFailed;
    out.message = id() + ": line search failed: " + result.message;
    return out;
  }

  const Vector moved = result.step * scale.cwiseProduct(pz);
  out.delta = domain.feasible_step(x, moved);
  const Vector sz = out.delta.cwiseQuotient(scale);
  const Vector yz = scale.cwiseProduct(result.gradient - g_);
  if (yz.dot(sz) > kCurvatureTolerance * sz.norm() * yz.norm()) add_pair(sz, yz);
  // The point the caller moves to, with its value and gradient when the line search evaluated
  // exactly there (a step cut to the box may differ in the last bits: evaluated afresh).
  x_ = domain.project(x + out.delta);
  if (x_ == x + moved) {
    value_ = result.value;
    g_ = std::move(result.gradient);
  } else {
    x_.resize(0);
  }
  return out;
}

}  // namespace physgrad
