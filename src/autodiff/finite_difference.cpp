#include "physgrad/autodiff/finite_difference.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/physics/checked_simulator.hpp"

namespace physgrad {

Matrix finite_difference_jacobian(const std::function<Vector(const Vector&)>& f, const Vector& x,
                                  double h) {
  Matrix jacobian;
  Vector shifted = x;
  for (Index i = 0; i < x.size(); ++i) {
    const double step = h * std::max(1.0, std::abs(x(i)));
    shifted(i) = x(i) + step;
    const Vector plus = f(shifted);
    shifted(i) = x(i) - step;
    const Vector minus = f(shifted);
    shifted(i) = x(i);
    if (i == 0) jacobian.resize(plus.size(), x.size());
    if (plus.size() != jacobian.rows() || minus.size() != jacobian.rows()) {
      std::ostringstream msg;
      msg << "finite differences: f returned " << plus.size() << " and " << minus.size()
          << " entries at component " << i << ", " << jacobian.rows() << " at component 0";
      throw Error(msg.str());
    }
    jacobian.col(i) = (plus - minus) / (2 * step);
  }
  return jacobian;
}

namespace {
// Both have the same shape (the simulator's results are checked). Infinite when either has a
// NaN or Inf entry (a maximum over entries would pass a NaN over).
double relative_error(const Matrix& actual, const Matrix& expected) {
  if (!all_finite(actual) || !all_finite(expected)) return INFINITY;
  if (actual.size() == 0) return 0;
  const double scale = std::max(1.0, expected.cwiseAbs().maxCoeff());
  return (actual - expected).cwiseAbs().maxCoeff() / scale;
}
}  // namespace

std::string DerivativeCheck::report() const {
  std::ostringstream out;
  out << "jacobian error " << jacobian_error << ", vjp error " << vjp_error
      << ", hessian error " << hessian_error << (passed ? " (passed)" : " (FAILED)");
  return out.str();
}

DerivativeCheck check_derivatives(const Simulator& user_simulator, const Vector& x,
                                  const Vector& context, double tolerance) {
  std::optional<CheckedSimulator> local;
  const CheckedSimulator& simulator = CheckedSimulator::around(user_simulator, local);
  if (x.size() != simulator.input_dim()) {
    std::ostringstream msg;
    msg << "check_derivatives: x has " << x.size() << " entries, simulator '"
        << simulator.name() << "' has input_dim " << simulator.input_dim();
    throw Error(msg.str());
  }
  DerivativeCheck check;
  const auto forward = [&](const Vector& at) { return simulator.forward(at, context); };
  const Matrix expected = finite_difference_jacobian(forward, x);
  check.jacobian_error = relative_error(simulator.jacobian(x, context), expected);

  // A fixed cotangent with entries of both signs and different magnitudes.
  Vector v(simulator.output_dim());
  for (Index k = 0; k < v.size(); ++k) v(k) = std::sin(1.0 + 2.3 * static_cast<double>(k));
  check.vjp_error = relative_error(simulator.vjp(x, context, v), expected.transpose() * v);

  const auto weighted_vjp = [&](const Vector& at) { return simulator.vjp(at, context, v); };
  check.hessian_error = relative_error(simulator.weighted_hessian(x, context, v),
                                       finite_difference_jacobian(weighted_vjp, x, 1e-5));
  check.passed = check.jacobian_error <= tolerance && check.vjp_error <= tolerance &&
                 check.hessian_error <= tolerance;
  return check;
}

double inverse_residual(const Simulator& user_simulator, const Vector& y, const Vector& x0,
                        const Vector& context) {
  std::optional<CheckedSimulator> local;
  const CheckedSimulator& simulator = CheckedSimulator::around(user_simulator, local);
  const Vector x = simulator.inverse(y, x0, context);
  return (simulator.forward(x, context) - y).norm() / std::max(1.0, y.norm());
}

}  // namespace physgrad
