#include "physgrad/physics/simulator.hpp"

#include <cmath>
#include <limits>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

void Simulator::check_batch(const Matrix& x, const Matrix& context, const char* where,
                            bool context_required) const {
  if (x.rows() != input_dim()) {
    std::ostringstream msg;
    msg << name() << "." << where << ": x has " << x.rows() << " rows, expected input_dim "
        << input_dim();
    throw Error(msg.str());
  }
  if (context_required && context.size() == 0) {
    std::ostringstream msg;
    msg << name() << "." << where << ": the context (" << context_dim()
        << " rows, one column per sample) is required";
    throw Error(msg.str());
  }
  const bool context_ok = context.size() == 0 ||
                          (context.rows() == context_dim() && context.cols() == x.cols());
  if (!context_ok) {
    std::ostringstream msg;
    msg << name() << "." << where << ": context is " << context.rows() << "×" << context.cols()
        << ", expected " << context_dim() << "×" << x.cols();
    throw Error(msg.str());
  }
}

void Simulator::check_vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy,
                                bool context_required) const {
  check_batch(x, context, "vjp", context_required);
  if (gy.rows() != output_dim() || gy.cols() != x.cols()) {
    std::ostringstream msg;
    msg << name() << ".vjp: gy is " << gy.rows() << "×" << gy.cols() << ", expected "
        << output_dim() << "×" << x.cols();
    throw Error(msg.str());
  }
}

Vector Simulator::forward(const Vector& x, const Vector& context) const {
  return forward_batch(x, context);
}

Vector Simulator::vjp(const Vector& x, const Vector& context, const Vector& gy) const {
  return vjp_batch(x, context, gy);
}

Matrix Simulator::jacobian(const Vector& x, const Vector& context) const {
  const Index m = output_dim();
  // Row k of J is (∂P/∂x)ᵀ e_k: one batch of m copies of x with the unit cotangents.
  const Matrix xs = x.replicate(1, m);
  const Matrix cs = context.size() == 0 ? Matrix() : Matrix(context.replicate(1, m));
  return vjp_batch(xs, cs, Matrix::Identity(m, m)).transpose();
}

Matrix Simulator::weighted_hessian(const Vector& x, const Vector& context,
                                   const Vector& w) const {
  const Index n = input_dim();
  // Column i: (VJP(x + h e_i) − VJP(x − h e_i)) / 2h, all 2n points in one batch.
  Matrix points = x.replicate(1, 2 * n);
  Vector h(n);
  for (Index i = 0; i < n; ++i) {
    h(i) = std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(x(i)));
    points(i, 2 * i) += h(i);
    points(i, 2 * i + 1) -= h(i);
  }
  const Matrix cs = context.size() == 0 ? Matrix() : Matrix(context.replicate(1, 2 * n));
  const Matrix g = vjp_batch(points, cs, w.replicate(1, 2 * n));
  Matrix hessian(n, n);
  for (Index i = 0; i < n; ++i) hessian.col(i) = (g.col(2 * i) - g.col(2 * i + 1)) / (2 * h(i));
  return 0.5 * (hessian + hessian.transpose());
}

Vector Simulator::inverse(const Vector& /*y*/, const Vector& /*x0*/,
                          const Vector& /*context*/) const {
  throw Error("simulator '" + name() + "' has no analytic local inverse");
}

Vector Simulator::time_reversal(const Vector& /*y*/, const Vector& /*context*/) const {
  throw Error("simulator '" + name() + "' has no time reversal");
}

}  // namespace physgrad
