// PoissonSolve — the SIP paper's Poisson problem: y = P(x) solves laplace(y) = x on an n×n grid
// of unit cells with Dirichlet-0 boundaries (5-point stencil, zero ghost cells); P⁻¹ = laplace.
#pragma once

#include "physgrad/physics/poisson.hpp"
#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// y = L⁻¹x with L the Laplacian of Poisson (cell (i, j) is entry i + n·j). L is symmetric, so the
// VJP is L⁻¹gy, a second solve; P is linear, so the weighted Hessian is 0. The reference solves by
// conjugate gradients to a relative residual of 1e-5; here a sparse Cholesky factor solves
// exactly (to round-off). The inverse is the Laplacian itself: P⁻¹(y) = laplace(y), the SIP
// correction x̃ = laplace(y*) for a step η = 1.
class PoissonSolve final : public Simulator {
 public:
  // Throws Error unless n ≥ 1 and the factor fits in memory (as Poisson).
  explicit PoissonSolve(Index n = 64) : laplacian_(n) {}

  std::string name() const override { return "poisson_solve"; }
  Index input_dim() const override { return laplacian_.input_dim(); }
  Index output_dim() const override { return laplacian_.output_dim(); }
  Index grid_size() const { return laplacian_.grid_size(); }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const override;

  // laplace(y), whatever x0 (checked for its size only): the exact inverse.
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const override;

 private:
  Poisson laplacian_;
};

}  // namespace physgrad
