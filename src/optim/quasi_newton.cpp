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
                                     const Vector& p) const {
  const double first = has_curvature() ? initial_step_
                                       : initial_step_ * std::min(1.0, 1 / p.stableNorm());
  if (!(first > 0 && std::isfinite(first))) {
    std::ostringstream msg;
    msg << "line search: the first trial step along a direction of norm " << p.stableNorm()
        << " is " << first;
    throw NumericalError(msg.str());
  }
  return strong_wolfe_line_search(objective, x, value_, g_, p, first, line_search_);
}

Step QuasiNewton::step(const Objective& objective, const Vector& x) {
  Step out;
  const Index n = x.size();
  if (!(x_.size() == n && x == x_)) {
    if (x_.size() != n) clear_curvature();
    value_ = objective.value_and_gradient(x, g_);
    x_ = x;
    ++out.evaluations;
  }
  if (!all_finite(g_)) throw NumericalError("the gradient at x is not finite");
  if ((g_.array() == 0).all()) {  // stationary point: a zero step ends the run
    out.dx = Vector::Zero(n);
    return out;
  }

  Vector p = direction(g_);
  LineSearchResult result = search(objective, x, p);
  out.evaluations += result.evaluations;
  if (!result.success && has_curvature()) {
    out.message = id() + ": restarted along −∇L after: " + result.message;
    clear_curvature();
    p = -g_;
    result = search(objective, x, p);
    out.evaluations += result.evaluations;
  }
  if (!result.success && result.evaluations > 0 && result.non_finite == result.evaluations) {
    throw NumericalError("line search: all " + std::to_string(result.evaluations) +
                         " trial points gave a non-finite loss or gradient");
  }
  if (!result.success) {
    out.status = Step::Status::kFailed;
    out.message = id() + ": line search failed: " + result.message;
    return out;
  }

  out.dx = result.step * p;
  const Vector y = result.gradient - g_;
  if (y.dot(out.dx) > kCurvatureTolerance * out.dx.norm() * y.norm()) add_pair(out.dx, y);
  x_ = x + out.dx;  // the point the caller moves to
  value_ = result.value;
  g_ = std::move(result.gradient);
  return out;
}

}  // namespace physgrad
