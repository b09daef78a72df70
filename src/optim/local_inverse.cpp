#include "physgrad/optim/local_inverse.hpp"

#include <cmath>
#include <memory>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/loss/loss.hpp"
#include "physgrad/optim/gauss_newton.hpp"
#include "physgrad/optim/lbfgs.hpp"
#include "physgrad/optim/minimize.hpp"

namespace physgrad {

std::string to_string(InverseMethod method) {
  switch (method) {
    case InverseMethod::kAuto: return "auto";
    case InverseMethod::kAnalytic: return "analytic";
    case InverseMethod::kLbfgs: return "lbfgs";
    case InverseMethod::kGaussNewton: return "gn";
  }
  return "unknown";
}

InverseMethod parse_inverse_method(const std::string& text) {
  for (InverseMethod method : {InverseMethod::kAuto, InverseMethod::kAnalytic,
                               InverseMethod::kLbfgs, InverseMethod::kGaussNewton}) {
    if (text == to_string(method)) return method;
  }
  throw Error("unknown inverse method '" + text + "' (known: auto, analytic, lbfgs, gn)");
}

LocalInverseResult local_inverse(const Simulator& simulator, const Vector& y, const Vector& x0,
                                 const Vector& context, const LocalInverseOptions& options) {
  if (y.size() != simulator.output_dim()) {
    std::ostringstream msg;
    msg << "local inverse: y has " << y.size() << " entries, simulator '" << simulator.name()
        << "' has output_dim " << simulator.output_dim();
    throw Error(msg.str());
  }
  InverseMethod method = options.method;
  if (method == InverseMethod::kAuto) {
    method = simulator.has_inverse() ? InverseMethod::kAnalytic : InverseMethod::kLbfgs;
  }
  LocalInverseResult result;
  if (method == InverseMethod::kAnalytic) {
    if (!simulator.has_inverse()) {
      throw Error("simulator '" + simulator.name() +
                  "' has no analytic inverse; use a numerical one (lbfgs or gn)");
    }
    result.x = simulator.inverse(y, x0, context);
    result.residual = (simulator.forward(result.x, context) - y).norm();
    result.converged = std::isfinite(result.residual);
    return result;
  }

  require_positive("local inverse: tolerance", options.tolerance);
  if (options.max_iterations < 1) throw Error("local inverse: max_iterations must be ≥ 1");
  const L2Loss half_squares;
  const Objective misfit(simulator, half_squares, y, context);
  std::unique_ptr<Optimizer> solver;
  if (method == InverseMethod::kLbfgs) {
    solver = std::make_unique<Lbfgs>();
  } else {
    solver = std::make_unique<GaussNewton>();
  }
  const double residual_tolerance = options.tolerance * (1 + y.norm());
  MinimizeOptions run;
  run.max_iterations = options.max_iterations;
  run.loss_tolerance = 0.5 * residual_tolerance * residual_tolerance;
  if (!std::isfinite(misfit.value(x0))) {
    result.x = Vector::Constant(x0.size(), NAN);
    result.residual = NAN;
    return result;
  }
  const MinimizeSummary summary = minimize(*solver, misfit, x0, run);
  if (summary.termination == Termination::kNumericalFailure) {
    throw NumericalError("local inverse (" + to_string(method) + "): " + summary.message);
  }
  result.x = summary.x;
  result.residual = std::sqrt(2 * summary.loss);
  result.iterations = summary.iterations;
  result.converged = result.residual <= residual_tolerance;
  return result;
}

}  // namespace physgrad
