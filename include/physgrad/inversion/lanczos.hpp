// Lanczos approximation of a matrix function applied to a vector: for a symmetric positive
// semi-definite A known only by its products, f(A) b ≈ ‖b‖ Q f(T) e₁ after q steps (A Q = Q T + r).
#pragma once

#include <functional>

#include "physgrad/types.hpp"

namespace physgrad {

// What q Lanczos steps from q₁ = b/‖b‖ give: the orthonormal basis Q of the Krylov space
// span{b, Ab, …, A^{q−1}b} (fully reorthogonalized, twice per step), the eigenvalues θ of the
// tridiagonal T = QᵀAQ (the Ritz values) and c = ‖b‖ f(T) e₁, so that f(A) b ≈ Q c. With q = n
// steps (or once the Krylov space is exhausted, which ends the iteration early) the
// approximation is exact up to rounding.
struct LanczosApproximation {
  Matrix basis;         // Q, n × steps
  Vector ritz_values;   // θ, the eigenvalues of T (in no particular order)
  Vector coefficients;  // c, `steps` entries
  Index steps = 0;      // steps made: fewer than asked when the Krylov space is exhausted
};

// `multiply(v)` returns A v (n entries for n = b.size()); `f(θ)` maps all Ritz values at once
// (so that a cut can be relative to the largest) to f(θ). A zero b gives zero coefficients after
// no step. Throws Error when steps < 1 or multiply returns the wrong size; NumericalError on a
// non-finite product or T.
LanczosApproximation lanczos_function(const std::function<Vector(const Vector&)>& multiply,
                                      const Vector& b, Index steps,
                                      const std::function<Vector(const Vector&)>& f);

}  // namespace physgrad
