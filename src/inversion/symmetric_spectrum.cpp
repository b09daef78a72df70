#include "symmetric_spectrum.hpp"

#include <cblas.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "physgrad/error.hpp"
#include "physgrad/inversion/tridiagonal_eigen.hpp"

namespace physgrad::inversion_detail {

lapack_int lapack_dim(Index n) {
  if (n > std::numeric_limits<lapack_int>::max()) {
    throw Error("power_pinv_apply: dimension " + std::to_string(n) + " too large for LAPACK");
  }
  return static_cast<lapack_int>(n);
}

void check_lapack(lapack_int status, const char* routine) {
  if (status != 0) {
    throw NumericalError(std::string("power_pinv_apply: LAPACK ") + routine + " failed (info = " +
                std::to_string(status) + ")");
  }
}

namespace {

// The product for eigenvectors held as the columns of `vectors`.
auto with_vectors(Matrix vectors) {
  return [v = std::move(vectors)](const Vector& weights, const Vector& x) -> Vector {
    return v * weights.cwiseProduct(v.transpose() * x);
  };
}

// h ← Q h (trans 'N') or Qᵀ h ('T') for W = Q T Qᵀ from sytrd (lower): Q's reflectors below the
// subdiagonal of `reduced`, their factors in `tau`.
void apply_reflectors(const Matrix& reduced, const Vector& tau, Vector& h, char trans) {
  const lapack_int n = lapack_dim(reduced.rows());
  check_lapack(LAPACKE_dormtr(LAPACK_COL_MAJOR, 'L', 'L', trans, n, 1, reduced.data(), n,
                              tau.data(), h.data(), n),
               "dormtr");
}

// The product for W = Q T Qᵀ and T = S Λ Sᵀ (S as rotations): Q S diag(weights) Sᵀ Qᵀ x,
// O(n²) — no eigenvector is formed.
auto with_tridiagonal(Matrix reduced, Vector tau, TridiagonalEigen t) {
  return [q = std::move(reduced), tau = std::move(tau), t = std::move(t)](
             const Vector& weights, const Vector& x) -> Vector {
    Vector h = x;
    apply_reflectors(q, tau, h, 'T');
    h = t.apply(t.apply_transpose(std::move(h)).cwiseProduct(weights));
    apply_reflectors(q, tau, h, 'N');
    return h;
  };
}

// LAPACK's symmetric eigensolvers for one scalar type: all pairs (syevd), or those with
// λ in (vl, ∞) (syevr by value range), lower triangle of the n × n `a` (overwritten).
lapack_int syevd(lapack_int n, double* a, double* w) {
  return LAPACKE_dsyevd(LAPACK_COL_MAJOR, 'V', 'L', n, a, n, w);
}
// With the workspace sizes LAPACK documents for ssyevd (1 + 6n + 2n² and 3 + 5n): LAPACKE's
// size query returns them as a float, which rounds 2n² down for n ≳ 2900 (ssyevd then fails).
lapack_int syevd(lapack_int n, float* a, float* w) {
  const auto count = static_cast<std::size_t>(n);
  std::vector<float> work(1 + 6 * count + 2 * count * count);
  std::vector<lapack_int> iwork(3 + 5 * count);
  return LAPACKE_ssyevd_work(LAPACK_COL_MAJOR, 'V', 'L', n, a, n, w, work.data(),
                             static_cast<lapack_int>(work.size()), iwork.data(),
                             static_cast<lapack_int>(iwork.size()));
}
lapack_int syevr(lapack_int n, double* a, double vl, lapack_int* found, double* w, double* z,
                 lapack_int* support) {
  return LAPACKE_dsyevr(LAPACK_COL_MAJOR, 'V', 'V', 'L', n, a, n, vl,
                        std::numeric_limits<double>::max(), 0, 0, 0.0, found, w, z, n, support);
}
lapack_int syevr(lapack_int n, float* a, float vl, lapack_int* found, float* w, float* z,
                 lapack_int* support) {
  return LAPACKE_ssyevr(LAPACK_COL_MAJOR, 'V', 'V', 'L', n, a, n, vl,
                        std::numeric_limits<float>::max(), 0, 0, 0.0f, found, w, z, n, support);
}
// The reduction W = Q T Qᵀ (lower triangle of `a`, overwritten by Q's reflectors): T's diagonal
// d (n), subdiagonal e (n − 1) and the reflectors' factors tau (n − 1).
lapack_int sytrd(lapack_int n, double* a, double* d, double* e, double* tau) {
  return LAPACKE_dsytrd(LAPACK_COL_MAJOR, 'L', n, a, n, d, e, tau);
}
lapack_int sytrd(lapack_int n, float* a, float* d, float* e, float* tau) {
  return LAPACKE_ssytrd(LAPACK_COL_MAJOR, 'L', n, a, n, d, e, tau);
}

}  // namespace

template <typename Scalar>
Spectrum solve_spectrum(Matrix& w, PinvEigensolver eigensolver, double vl, const SpectralCut& cut) {
  using ScalarMatrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using ScalarVector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  constexpr bool kIsFloat = std::is_same_v<Scalar, float>;
  const lapack_int n = lapack_dim(w.rows());
  const bool subset = eigensolver == PinvEigensolver::kSubset;
  Spectrum out;
  out.precision = kIsFloat ? PinvPrecision::kFloat : PinvPrecision::kDouble;
  out.eigensolver = eigensolver;
  ScalarMatrix copy;
  Scalar* a = nullptr;
  if constexpr (kIsFloat) {
    copy = w.cast<float>();
    a = copy.data();
  } else {
    if (subset) copy = w;
    a = subset ? copy.data() : w.data();
  }
  // The matrix a's solve left behind, in double (w itself when it was solved in place).
  const auto solved = [&]() -> Matrix {
    if constexpr (kIsFloat) {
      return copy.template cast<double>();
    } else {
      return std::move(w);
    }
  };
  ScalarVector lambda(n);
  switch (eigensolver) {
    case PinvEigensolver::kSubset: {
      ScalarMatrix z(n, n);
      std::vector<lapack_int> support(2 * static_cast<std::size_t>(n));
      lapack_int found = 0;
      check_lapack(syevr(n, a, static_cast<Scalar>(vl), &found, lambda.data(), z.data(),
                         support.data()),
                   kIsFloat ? "ssyevr" : "dsyevr");
      out.lambda = lambda.head(found).template cast<double>();
      out.apply = with_vectors(z.leftCols(found).template cast<double>());
      break;
    }
    case PinvEigensolver::kTridiagonal: {
      const Index off = std::max<Index>(n - 1, 1);
      ScalarVector e(off), tau(off);
      check_lapack(sytrd(n, a, lambda.data(), e.data(), tau.data()),
                   kIsFloat ? "ssytrd" : "dsytrd");
      TridiagonalEigen t(lambda.template cast<double>(), e.head(n - 1).template cast<double>());
      out.lambda = t.eigenvalues();
      out.apply = with_tridiagonal(solved(), tau.template cast<double>(), std::move(t));
      break;
    }
    default:
      check_lapack(syevd(n, a, lambda.data()), kIsFloat ? "ssyevd" : "dsyevd");
      out.lambda = lambda.template cast<double>();
      out.apply = with_vectors(solved());
  }
  // Eigenvalues ≤ vl that a subset left out must lie clearly below the cut for the check.
  if (out.lambda.size() > 0) {
    const FloatBounds bounds(n, out.lambda.maxCoeff(), cut);
    const bool complete = out.lambda.size() == n || vl <= bounds.dropped_below;
    out.float_resolves = complete && bounds.resolves(out.lambda);
  }
  return out;
}

double lambda_max_lower_bound(const Matrix& w) {
  const lapack_int n = lapack_dim(w.rows());
  double bound = w.diagonal().maxCoeff();
  Vector v = Vector::Ones(n) / std::sqrt(static_cast<double>(n));
  Vector u(n);
  for (int iteration = 0; iteration < 8; ++iteration) {
    cblas_dsymv(CblasColMajor, CblasLower, n, 1.0, w.data(), n, v.data(), 1, 0.0, u.data(), 1);
    bound = std::max(bound, v.dot(u));  // v has unit length
    const double norm = u.norm();
    if (!(norm > 0)) break;
    v = u / norm;
  }
  return bound;
}

template Spectrum solve_spectrum<double>(Matrix&, PinvEigensolver, double, const SpectralCut&);
template Spectrum solve_spectrum<float>(Matrix&, PinvEigensolver, double, const SpectralCut&);

}  // namespace physgrad::inversion_detail
