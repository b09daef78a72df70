// Jacobians of known singular values — J = U diag(s) Vᵀ from random orthonormal U and V, and the
// power-pseudo-inverse they imply, V diag(s^{−κ}) Uᵀ g over s > rcond·max(s).
#pragma once

#include <cmath>

#include "physgrad/types.hpp"
#include "test_problems.hpp"

namespace physgrad::testing {

// n×k with orthonormal columns: the Q factor of a Householder QR of a random matrix.
inline Matrix random_orthonormal(Index n, Index k, unsigned seed) {
  const Eigen::HouseholderQR<Matrix> qr(testing::random_normal(n, k, seed));
  return qr.householderQ() * Matrix::Identity(n, k);
}

// count values from 1 down to lo, evenly spaced in log.
inline Vector log_spaced(Index count, double lo) {
  Vector s(count);
  for (Index k = 0; k < count; ++k) {
    s(k) = std::pow(lo, static_cast<double>(k) / static_cast<double>(count - 1));
  }
  return s;
}

// J = U diag(s) Vᵀ with known orthonormal U (rows × |s|) and V (cols × |s|).
struct Factored {
  Matrix u;
  Vector s;
  Matrix v;
  Matrix j;
};

inline Factored factored(Index rows, Index cols, const Vector& s, unsigned seed) {
  Factored f{random_orthonormal(rows, s.size(), seed), s,
             random_orthonormal(cols, s.size(), seed + 1), Matrix()};
  f.j = f.u * s.asDiagonal() * f.v.transpose();
  return f;
}

// V diag(s^{−κ}) Uᵀ g over s > rcond·max(s), from the known factors.
inline Vector formula(const Factored& f, const Vector& g, double kappa, double rcond) {
  const double cutoff = rcond * f.s.maxCoeff();
  Vector c = f.u.transpose() * g;
  for (Index i = 0; i < c.size(); ++i) c(i) = f.s(i) > cutoff ? c(i) * std::pow(f.s(i), -kappa) : 0;
  return f.v * c;
}

inline double relative_error(const Vector& x, const Vector& ref) { return (x - ref).norm() / ref.norm(); }

}  // namespace physgrad::testing
