// FidelityLoss — the infidelity of a complex state against a target state.
// L(ψ; ψ*) = 1 − |⟨ψ*|ψ⟩|², ⟨a|b⟩ = Σ_j conj(a_j) b_j.
#pragma once

#include "physgrad/loss/loss.hpp"

namespace physgrad {

// y and y* hold complex vectors of M entries as 2M reals, [Re ψ₁ … Re ψ_M, Im ψ₁ … Im ψ_M]
// (the QuantumDipole layout). With a = Re⟨ψ*|ψ⟩ = y*·y and b = Im⟨ψ*|ψ⟩ = (−Im ψ*, Re ψ*)·y,
// both linear in y: L = 1 − a² − b², ∂L/∂y = −2(a∇a + b∇b), ∂²L/∂y² = −2(∇a∇aᵀ + ∇b∇bᵀ).
// Every method throws Error when the sizes differ or are odd.
class FidelityLoss final : public Loss {
 public:
  std::string name() const override { return "fidelity"; }
  double value(const Vector& y, const Vector& target) const override;
  Vector gradient(const Vector& y, const Vector& target) const override;
  Matrix hessian(const Vector& y, const Vector& target) const override;
  // The Hessian has rank ≤ 2 (∇a ⊥ ∇b, ‖∇a‖ = ‖∇b‖ = ‖y*‖), so the step is the minimum-norm
  // Δy = −H⁺g = −(a∇a + b∇b)/‖y*‖² (0 for y* = 0). L is concave in y, so this step leads to
  // the stationary point a = b = 0 of the quadratic model, where L = 1.
  Vector newton_step(const Vector& y, const Vector& target) const override;
};

}  // namespace physgrad
