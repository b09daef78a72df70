#include "physgrad/inversion/lanczos.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "physgrad/error.hpp"
#include "physgrad/inversion/tridiagonal_eigen.hpp"

namespace physgrad {

LanczosApproximation lanczos_function(const std::function<Vector(const Vector&)>& multiply,
                                      const Vector& b, Index steps,
                                      const std::function<Vector(const Vector&)>& f) {
  if (steps < 1) {
    throw Error("lanczos_function: steps must be ≥ 1, got " + std::to_string(steps));
  }
  if (!all_finite(b)) throw NumericalError("lanczos_function: non-finite entry in b");
  const Index n = b.size();
  const double norm = b.norm();
  LanczosApproximation out;
  if (norm == 0 || n == 0) {
    out.basis.resize(n, 0);
    return out;
  }
  steps = std::min(steps, n);
  Matrix q(n, steps);
  Vector alpha(steps), beta(steps);
  q.col(0) = b / norm;
  Index made = 0;
  double scale = 0;  // the largest |α|, β so far: the size of T
  for (Index j = 0; j < steps; ++j) {
    Vector w = multiply(q.col(j));
    if (w.size() != n) {
      throw Error("lanczos_function: the product has " + std::to_string(w.size()) +
                  " entries, expected " + std::to_string(n));
    }
    if (!all_finite(w)) throw NumericalError("lanczos_function: non-finite product A q");
    alpha(j) = q.col(j).dot(w);
    // Full reorthogonalization against every basis vector, twice (classical Gram-Schmidt): the
    // three-term recurrence alone loses orthogonality as soon as a Ritz value converges.
    for (int pass = 0; pass < 2; ++pass) {
      w.noalias() -= q.leftCols(j + 1) * (q.leftCols(j + 1).transpose() * w);
    }
    made = j + 1;
    scale = std::max(scale, std::abs(alpha(j)));
    if (j + 1 == steps) break;
    beta(j) = w.norm();
    scale = std::max(scale, beta(j));
    // The Krylov space is exhausted (b lies in an invariant subspace): T is exact.
    if (beta(j) <= 8 * std::numeric_limits<double>::epsilon() * static_cast<double>(n) * scale) {
      break;
    }
    q.col(j + 1) = w / beta(j);
  }
  const TridiagonalEigen eigen(alpha.head(made), beta.head(std::max<Index>(made - 1, 0)));
  out.ritz_values = eigen.eigenvalues();
  Vector values = f(out.ritz_values);
  if (values.size() != made) {
    throw Error("lanczos_function: f returned " + std::to_string(values.size()) +
                " values for " + std::to_string(made) + " Ritz values");
  }
  // c = ‖b‖ S f(Λ) Sᵀ e₁.
  Vector first = Vector::Zero(made);
  first(0) = 1;
  Vector projected = eigen.apply_transpose(first);
  projected.array() *= values.array();
  out.coefficients = norm * eigen.apply(projected);
  out.basis = q.leftCols(made);
  out.steps = made;
  return out;
}

}  // namespace physgrad
