#include "physgrad/physics/poisson_solve.hpp"

#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

Matrix PoissonSolve::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward");
  return laplacian_.solve_batch(x);
}

Matrix PoissonSolve::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_vjp_batch(x, context, gy);
  return laplacian_.solve_batch(gy);
}

Matrix PoissonSolve::weighted_hessian(const Vector& x, const Vector& context,
                                      const Vector& /*w*/) const {
  check_batch(x, context, "weighted_hessian");
  return Matrix::Zero(x.size(), x.size());
}

Vector PoissonSolve::inverse(const Vector& y, const Vector& x0, const Vector& context) const {
  check_batch(x0, context, "inverse");
  if (y.size() != output_dim()) {
    std::ostringstream msg;
    msg << name() << ".inverse: y has " << y.size() << " entries, expected " << output_dim();
    throw Error(msg.str());
  }
  return laplacian_.laplace(y);
}

}  // namespace physgrad
