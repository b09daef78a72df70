#include "physgrad/physics/comparison_toy.hpp"

#include <cmath>

#include "physgrad/error.hpp"

namespace physgrad {

Matrix ComparisonToy::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward");
  Matrix y(2, x.cols());
  y.row(0) = x.row(0);
  y.row(1) = x.row(1).array().square().matrix();
  return y;
}

Matrix ComparisonToy::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_vjp_batch(x, context, gy);
  Matrix gx(2, x.cols());
  gx.row(0) = gy.row(0);
  gx.row(1) = 2.0 * x.row(1).cwiseProduct(gy.row(1));
  return gx;
}

Matrix ComparisonToy::weighted_hessian(const Vector& x, const Vector& context,
                                       const Vector& w) const {
  check_batch(x, context, "weighted_hessian");
  Matrix h = Matrix::Zero(2, 2);
  h(1, 1) = 2.0 * w(1);  // ∂²(x₁²)/∂x₁² = 2
  return h;
}

Vector ComparisonToy::inverse(const Vector& y, const Vector& x0, const Vector& context) const {
  check_batch(x0, context, "inverse");
  if (y.size() != 2) throw Error("comparison_toy.inverse: y must have 2 entries");
  const double root = std::sqrt(std::max(y(1), 0.0));
  return Vector{{y(0), x0(1) < 0 ? -root : root}};
}

}  // namespace physgrad
