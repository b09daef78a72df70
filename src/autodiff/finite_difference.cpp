#include "physgrad/autodiff/finite_difference.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

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
    jacobian.col(i) = (plus - minus) / (2 * step);
  }
  return jacobian;
}

namespace {
double relative_error(const Matrix& actual, const Matrix& expected) {
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols()) return INFINITY;
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

DerivativeCheck check_derivatives(const Simulator& simulator, const Vector& x,
                                  const Vector& context, double tolerance) {
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

double inverse_residual(const Simulator& simulator, const Vector& y, const Vector& x0,
                        const Vector& context) {
  const Vector x = simulator.inverse(y, x0, context);
  return (simulator.forward(x, context) - y).norm() / std::max(1.0, y.norm());
}

}  // namespace physgrad
