// The eigendecomposition T = S Λ Sᵀ of a symmetric tridiagonal matrix T, with S kept as the
// plane rotations of the implicit QL iteration that diagonalizes T. S v and Sᵀ v then cost one
// pass over the rotations (about n² of them, 16 bytes each; 1.02–1.11 n² measured on Gram
// matrices), and S itself is never formed: f(T) v = S f(Λ) Sᵀ v without the n³ work of
// eigenvectors. power_pinv.hpp's "tridiagonal" eigensolver uses it on the tridiagonal form of
// J Jᵀ or JᵀJ.
#pragma once

#include <cstddef>
#include <vector>

#include "physgrad/types.hpp"

namespace physgrad {

class TridiagonalEigen {
 public:
  // T with the n entries of `diagonal` and the n − 1 of `subdiagonal` (entry i couples rows i
  // and i + 1). The iteration works on T scaled by a power of two (exact) to a largest entry of
  // order 1, turned so that its larger end is at the bottom; each eigenvalue is accurate to a
  // few ε·‖T‖, as with LAPACK's QL/QR (dsteqr). Throws Error when the sizes do not match,
  // NumericalError on a non-finite entry or when the iteration has not converged after 30·n
  // sweeps.
  TridiagonalEigen(Vector diagonal, const Vector& subdiagonal);

  // λ_i, the eigenvalue of column i of S (in the order the iteration leaves them, not sorted).
  const Vector& eigenvalues() const { return lambda_; }
  Vector apply(Vector v) const;            // S v
  Vector apply_transpose(Vector v) const;  // Sᵀ v
  std::size_t rotations() const { return rotations_.size(); }

 private:
  struct Rotation {
    double c, s;
  };
  // The rotations of one QL sweep act on rows (top, top + 1), (top − 1, top), … in this order.
  struct Sweep {
    Index top;
    std::size_t first, count;  // their range in rotations_
  };

  void iterate(Vector& e);

  Vector lambda_;
  bool reversed_ = false;  // T was iterated upside down (see the constructor)
  std::vector<Rotation> rotations_;
  std::vector<Sweep> sweeps_;
};

}  // namespace physgrad
