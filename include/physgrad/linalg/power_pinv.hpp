// Truncated power-pseudo-inverse applied to a vector: J^{−κ} g = V diag(σᵢ^{−κ}) Uᵀ g over the
// singular values σᵢ > rcond·σ_max of J = U Σ Vᵀ; the others contribute nothing (κ = 1: J⁺ g).
#pragma once

#include "physgrad/types.hpp"

namespace physgrad {

struct PowerPinvOptions {
  double kappa = 1.0;    // exponent: 1 = pseudo-inverse (Gauss-Newton, IG), 0.5 = HIG
  double rcond = 1e-10;  // keep σᵢ > rcond·σ_max (strictly); 0 ≤ rcond < 1
};

// Thin SVD of J (Eigen's divide-and-conquer BDCSVD). Throws Error on mismatched sizes,
// non-finite entries or options out of range.
Vector power_pinv_apply(const Matrix& j, const Vector& g, const PowerPinvOptions& options = {});

// Truncated pseudo-inverse of a symmetric positive semi-definite matrix applied to g:
// A⁺ g over the eigenvalues λᵢ > rcond·λ_max (the normal-equation solve of Gauss-Newton).
Vector symmetric_pinv_apply(const Matrix& a, const Vector& g, double rcond = 1e-12);

}  // namespace physgrad
