#include "physgrad/inversion/tridiagonal_eigen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

// √(f² + g²); below ~1e-150 the squares lose digits to underflow and hypot takes over.
double radius(double f, double g) {
  const double r = std::sqrt(f * f + g * g);
  return r > 1e-150 ? r : std::hypot(f, g);
}

void check_vector_size(const Vector& v, Index n, const char* what) {
  if (v.size() != n) {
    throw Error(std::string("TridiagonalEigen::") + what + ": the vector has " +
                std::to_string(v.size()) + " entries, T is " + std::to_string(n) + " × " +
                std::to_string(n));
  }
}

}  // namespace

TridiagonalEigen::TridiagonalEigen(Vector diagonal, const Vector& subdiagonal)
    : lambda_(std::move(diagonal)) {
  const Index n = lambda_.size();
  if (subdiagonal.size() != std::max<Index>(n - 1, 0)) {
    throw Error("TridiagonalEigen: " + std::to_string(n) + " diagonal entries need " +
                std::to_string(std::max<Index>(n - 1, 0)) + " subdiagonal ones, got " +
                std::to_string(subdiagonal.size()));
  }
  if (!all_finite(lambda_) || !all_finite(subdiagonal)) {
    throw NumericalError("TridiagonalEigen: non-finite entry in T");
  }
  if (n < 2) return;
  Vector e(n);  // e(n − 1) = 0 closes the last block
  e.head(n - 1) = subdiagonal;
  e(n - 1) = 0;
  // QL resolves the small eigenvalues of a graded T to its own accuracy only when the larger
  // entries sit at the bottom (LAPACK's dsteqr chooses between QL and QR per block for this
  // reason); the tridiagonal form of a Gram matrix has them at the top, where QL lost a factor
  // of ~10 in the step's accuracy on spectra spanning 1e-6. So T is iterated upside down
  // (P T P, P the reversal) when its last diagonal entry is the smaller one: S = P S'.
  reversed_ = std::abs(lambda_(n - 1)) < std::abs(lambda_(0));
  if (reversed_) {
    lambda_.reverseInPlace();
    e.head(n - 1).reverseInPlace();
  }
  const double largest = std::max(lambda_.cwiseAbs().maxCoeff(), e.cwiseAbs().maxCoeff());
  if (largest == 0) return;
  int exponent = 0;
  std::frexp(largest, &exponent);
  lambda_ *= std::ldexp(1.0, -exponent);
  e *= std::ldexp(1.0, -exponent);
  // 1.02–1.11 n² rotations were measured on Gram matrices; a T that needs more grows the vector.
  rotations_.reserve(static_cast<std::size_t>(n) * static_cast<std::size_t>(n) * 5 / 4);
  iterate(e);
  lambda_ *= std::ldexp(1.0, exponent);
}

// The implicit QL iteration with Wilkinson shifts on lambda_ (the diagonal) and e: for each l,
// sweeps chase the shift's bulge from the end m of l's unreduced block up to l until e(l) is
// negligible (|e(m)| ≤ ε·(|d(m)| + |d(m + 1)|) splits T there) and d(l) is an eigenvalue. Every
// sweep's rotations are recorded in order; S is their product.
void TridiagonalEigen::iterate(Vector& e) {
  Vector& d = lambda_;
  const Index n = d.size();
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  const Index max_sweeps = 30 * n;
  Index total = 0;
  for (Index l = 0; l < n; ++l) {
    for (;;) {
      Index m = l;
      while (m < n - 1 && std::abs(e(m)) > kEps * (std::abs(d(m)) + std::abs(d(m + 1)))) ++m;
      if (m == l) break;
      if (++total > max_sweeps) {
        throw NumericalError("TridiagonalEigen: the QL iteration did not converge in " +
                             std::to_string(max_sweeps) + " sweeps (n = " + std::to_string(n) +
                             ")");
      }
      // The shift: the eigenvalue of T's leading 2 × 2 block at l that is closer to d(l).
      double g = (d(l + 1) - d(l)) / (2 * e(l));
      double r = std::sqrt(g * g + 1);
      g = d(m) - d(l) + e(l) / (g + std::copysign(r, g));
      double s = 1, c = 1, p = 0;
      const std::size_t first = rotations_.size();
      bool split = false;
      for (Index i = m - 1; i >= l; --i) {
        const double f = s * e(i), b = c * e(i);
        r = radius(f, g);
        e(i + 1) = r;
        if (r == 0) {  // f = g = 0: T splits below row i, the sweep ends here
          d(i + 1) -= p;
          e(m) = 0;
          split = true;
          break;
        }
        s = f / r;
        c = g / r;
        g = d(i + 1) - p;
        r = (d(i) - g) * s + 2 * c * b;
        p = s * r;
        d(i + 1) = g + p;
        g = c * r - b;
        rotations_.push_back({c, s});
      }
      if (rotations_.size() > first) sweeps_.push_back({m - 1, first, rotations_.size() - first});
      if (split) continue;
      d(l) -= p;
      e(l) = g;
      e(m) = 0;
    }
  }
}

// Sᵀ v = G_Kᵀ ⋯ G_1ᵀ (P v) for S = P G_1 ⋯ G_K (P the reversal when T was iterated upside
// down, else the identity): the rotations in the order they were made.
Vector TridiagonalEigen::apply_transpose(Vector v) const {
  check_vector_size(v, lambda_.size(), "apply_transpose");
  if (reversed_) v.reverseInPlace();
  double* x = v.data();
  for (const Sweep& sweep : sweeps_) {
    Index i = sweep.top;
    for (std::size_t k = sweep.first; k < sweep.first + sweep.count; ++k, --i) {
      const auto [c, s] = rotations_[k];
      const double a = x[i], b = x[i + 1];
      x[i] = c * a - s * b;
      x[i + 1] = s * a + c * b;
    }
  }
  return v;
}

// S v = P G_1 ⋯ G_K v: the rotations in reverse order.
Vector TridiagonalEigen::apply(Vector v) const {
  check_vector_size(v, lambda_.size(), "apply");
  double* x = v.data();
  for (auto sweep = sweeps_.rbegin(); sweep != sweeps_.rend(); ++sweep) {
    Index i = sweep->top - static_cast<Index>(sweep->count) + 1;
    for (std::size_t k = sweep->first + sweep->count; k-- > sweep->first; ++i) {
      const auto [c, s] = rotations_[k];
      const double a = x[i], b = x[i + 1];
      x[i] = c * a + s * b;
      x[i + 1] = c * b - s * a;
    }
  }
  if (reversed_) v.reverseInPlace();
  return v;
}

}  // namespace physgrad
