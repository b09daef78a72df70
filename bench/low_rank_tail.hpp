// Low rank plus a flat tail, the candidate the structured rules measured against Lanczos: the top k
// eigenpairs U Λ Uᵀ of J Jᵀ by randomized subspace iteration, the rest of the spectrum by one
// value λ_t = (tr J Jᵀ − Σ Λ)/(n − k); f(J Jᵀ) g ≈ U f(Λ) Uᵀ g + f(λ_t)(g − U Uᵀ g).
#pragma once

#include <algorithm>
#include <cmath>
#include <random>

#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/learn/stacked_jacobian.hpp"

namespace physgrad::bench {

// Δθ = −η Jᵀ f(J Jᵀ) g with f(λ) = λ^{−(1+κ)/2} on λ > τ²λ_max and the approximation above: k
// random start vectors (seeded), `power` subspace iterations, then the Rayleigh-Ritz step. Costs
// k·(power + 2) products J Jᵀ v (and the trace, taken here from J Jᵀ's diagonal, which an
// estimator would give in training); *products receives that count.
inline Vector low_rank_tail_step(const StackedJacobian& j, const Vector& g, Index k, int power,
                                 double kappa, double rcond, double lr, unsigned seed,
                                 Index* products) {
  const Index n = j.rows();
  k = std::min(k, n);
  const auto times_gram = [&j](const Matrix& block) {
    Matrix out(block.rows(), block.cols());
    for (Index c = 0; c < block.cols(); ++c) out.col(c) = j.apply(j.apply_transpose(block.col(c)));
    return out;
  };
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Matrix y(n, k);
  for (Index i = 0; i < y.size(); ++i) y.data()[i] = normal(rng);
  const auto orthonormal = [](const Matrix& m) {
    const Eigen::HouseholderQR<Matrix> qr(m);
    return Matrix(qr.householderQ() * Matrix::Identity(m.rows(), m.cols()));
  };
  y = times_gram(y);
  for (int p = 0; p < power; ++p) y = times_gram(orthonormal(y));
  const Matrix q = orthonormal(y);
  const Matrix projected = q.transpose() * times_gram(q);
  const Eigen::SelfAdjointEigenSolver<Matrix> eigen(0.5 * (projected + projected.transpose()));
  const Matrix u = q * eigen.eigenvectors();
  const Vector& lambda = eigen.eigenvalues();
  const double trace = j.gram().diagonal().sum();
  const double tail = n > k ? std::max(0.0, (trace - lambda.sum()) / static_cast<double>(n - k)) : 0;
  const double cut = std::pow(std::max(rcond, kMinGramRcond), 2) * lambda.maxCoeff();
  const double exponent = -0.5 * (1 + kappa);
  const auto f = [&](double value) { return value > cut ? std::pow(value, exponent) : 0.0; };
  const Vector coefficients = u.transpose() * g;
  Vector weighted = coefficients;
  for (Index i = 0; i < weighted.size(); ++i) weighted(i) *= f(lambda(i));
  const Vector result = u * weighted + f(tail) * (g - u * coefficients);
  if (products != nullptr) *products = k * (power + 2);
  return -lr * j.apply_transpose(result);
}

}  // namespace physgrad::bench
