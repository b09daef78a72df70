#include "physgrad/physics/diagonal_scale.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

DiagonalScale::DiagonalScale(Vector scales) : scales_(std::move(scales)) {
  if (scales_.size() == 0) throw Error("diagonal_scale: needs at least one scale");
  for (Index i = 0; i < scales_.size(); ++i) {
    if (!std::isfinite(scales_(i)) || scales_(i) == 0) {
      std::ostringstream msg;
      msg << "diagonal_scale: scale " << i << " must be finite and nonzero, got " << scales_(i);
      throw Error(msg.str());
    }
  }
}

Matrix DiagonalScale::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward");
  return scales_.asDiagonal() * x;
}

Matrix DiagonalScale::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_batch(x, context, "vjp");
  return scales_.asDiagonal() * gy;
}

Matrix DiagonalScale::jacobian(const Vector& x, const Vector& context) const {
  check_batch(x, context, "jacobian");
  return scales_.asDiagonal();
}

Matrix DiagonalScale::weighted_hessian(const Vector& x, const Vector& context,
                                       const Vector& /*w*/) const {
  check_batch(x, context, "weighted_hessian");
  return Matrix::Zero(x.size(), x.size());
}

Vector DiagonalScale::inverse(const Vector& y, const Vector& x0, const Vector& context) const {
  check_batch(x0, context, "inverse");
  if (y.size() != output_dim()) throw Error("diagonal_scale.inverse: y has the wrong size");
  return y.cwiseQuotient(scales_);
}

}  // namespace physgrad
