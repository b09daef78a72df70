// ComparisonToy — the optimizer-comparison function P(x₀, x₁) = (x₀, x₁²); with L = ‖y‖²
// it gives L(x) = x₀² + x₁⁴. Local inverse: (y₀, ±√y₁) with the sign of the guess's x₁.
#pragma once

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

class ComparisonToy final : public Simulator {
 public:
  std::string name() const override { return "comparison_toy"; }
  Index input_dim() const override { return 2; }
  Index output_dim() const override { return 2; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const override;

  // The preimage nearest x0. For y₁ < 0 no real preimage exists; x₁ = 0 (the point whose
  // output is nearest y) is returned.
  bool has_inverse() const override { return true; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const override;
};

}  // namespace physgrad
