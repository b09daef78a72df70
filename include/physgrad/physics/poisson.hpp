// Poisson — the 5-point Laplacian on an n×n grid of unit cells with zero ghost cells.
// y_ij = x_{i−1,j} + x_{i+1,j} + x_{i,j−1} + x_{i,j+1} − 4x_ij (out-of-grid neighbours are 0).
#pragma once

#include <memory>

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// P(x) = laplace(x) with Dirichlet-0 boundaries; cell (i, j) is entry i + n·j of x and y.
// Linear and symmetric, so the VJP is laplace(gy) and the weighted Hessian is 0. The inverse
// solves laplace(x) = y exactly with a sparse Cholesky factor of −L computed once.
class Poisson final : public Simulator {
 public:
  // Throws Error unless n ≥ 1 and the Laplacian and its factor fit in memory
  // (physgrad/memory.hpp).
  explicit Poisson(Index n = 8);

  std::string name() const override { return "poisson"; }
  Index input_dim() const override { return n_ * n_; }
  Index output_dim() const override { return n_ * n_; }
  Index grid_size() const { return n_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const override;

  // The unique x with laplace(x) = y; x0 is only checked for its size.
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const override;
  // The x with laplace(x) = y for every column of y (n² × B): one solve per column with the
  // Cholesky factor; throws Error unless y has n² rows.
  Matrix solve_batch(const Matrix& y) const;
  // laplace(x) of every column, unchecked (the simulator's forward without its shape checks).
  Matrix laplace(const Matrix& x) const;

 private:

  struct Factor;
  Index n_;
  std::shared_ptr<const Factor> factor_;
};

}  // namespace physgrad
