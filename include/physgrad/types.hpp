// Common numeric types: double-precision Eigen vectors and matrices.
// Batches hold one sample per column (column-major, contiguous).
#pragma once

#include <Eigen/Dense>
#include <limits>

namespace physgrad {

using Index = Eigen::Index;
using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// True when every entry is finite (no NaN, no ±Inf).
template <typename Derived>
bool all_finite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}

}  // namespace physgrad
