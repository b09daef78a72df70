// DiagonalScale — the linear "physics" P(x) = diag(s)·x that scales each component.
// s = (1, α) is the scaled toy problem; a single s = α is the 1-D sensitivity example.
#pragma once

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

class DiagonalScale final : public Simulator {
 public:
  // Throws Error unless every scale is finite and nonzero (P must stay invertible).
  explicit DiagonalScale(Vector scales);

  std::string name() const override { return "diagonal_scale"; }
  Index input_dim() const override { return scales_.size(); }
  Index output_dim() const override { return scales_.size(); }
  const Vector& scales() const { return scales_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  Matrix jacobian(const Vector& x, const Vector& context = {}) const override;
  bool has_jacobian() const override { return true; }
  Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const override;

  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const override;

 private:
  Vector scales_;
};

}  // namespace physgrad
