// The symmetric eigensolves of the Gram and normal paths of power_pinv_apply() (private to
// src/inversion/): W = V Λ Vᵀ by dsyevd, dsyevr or dsytrd + QL, and f(W)·x = V f(Λ) Vᵀ x.
#pragma once

#include <lapacke.h>

#include <functional>

#include "physgrad/inversion/power_pinv.hpp"

namespace physgrad::inversion_detail {

// n as LAPACK's integer; Error when it does not fit.
lapack_int lapack_dim(Index n);
// NumericalError naming `routine` unless `status` is 0.
void check_lapack(lapack_int status, const char* routine);

// The float check's bounds for an n × n spectrum with largest eigenvalue λ_max: the float
// eigenvalue error δ, the smallest clearly kept value and the largest clearly dropped one.
struct FloatBounds {
  double kept_from, dropped_below;
  FloatBounds(Index n, double lambda_max, const SpectralCut& cut) {
    const double delta = std::sqrt(static_cast<double>(n)) *
                         std::numeric_limits<float>::epsilon() * lambda_max;
    const double cut2 = cut.lambda_cut(lambda_max);
    kept_from = std::max(kFloatAccuracy * delta, cut2 + delta);
    dropped_below = cut2 - delta;
  }
  bool resolves(const Vector& lambda) const {
    return (lambda.array() >= kept_from || lambda.array() <= dropped_below).all();
  }
};

// What an eigensolve of the symmetric n × n matrix W gives the step: every eigenvalue the cut may
// keep (in double, in the solver's order) and the product Σᵢ weightsᵢ·vᵢvᵢᵀx over their
// eigenvectors vᵢ, whichever way the solver holds them.
struct Spectrum {
  Vector lambda;
  std::function<Vector(const Vector& weights, const Vector& x)> apply;
  PinvPrecision precision = PinvPrecision::kDouble;
  PinvEigensolver eigensolver = PinvEigensolver::kFull;
  bool float_resolves = false;
};

// The spectrum of the symmetric `w` (lower triangle, consumed) in Scalar (double or float)
// arithmetic by `eigensolver` (kSubset: the pairs with λ > vl). Double full and tridiagonal solves
// work in place on `w`; the others on copies. The tridiagonal form of a float solve is kept in
// double (its reflectors and T rounded to float), so only the reduction runs in float.
template <typename Scalar>
Spectrum solve_spectrum(Matrix& w, PinvEigensolver eigensolver, double vl, const SpectralCut& cut);
extern template Spectrum solve_spectrum<double>(Matrix&, PinvEigensolver, double,
                                                const SpectralCut&);
extern template Spectrum solve_spectrum<float>(Matrix&, PinvEigensolver, double,
                                               const SpectralCut&);

// A lower bound of λ_max of the symmetric positive semi-definite w (lower triangle): the
// largest of its diagonal entries and of the Rayleigh quotients of a few power iterations.
double lambda_max_lower_bound(const Matrix& w);

}  // namespace physgrad::inversion_detail
