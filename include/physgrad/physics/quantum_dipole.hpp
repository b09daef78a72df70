// QuantumDipole — a controlled 1-D Schrödinger equation, Crank-Nicolson in time.
// iψ' = Hψ, H = −D₂ + u(t)·x; (I + i dt/2 H) ψⁿ⁺¹ = (I − i dt/2 H) ψⁿ, D₂ = tridiag(1, −2, 1)/dx².
#pragma once

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// Grid and time stepping. The domain [0, length] has `points` grid points (dx =
// length/(points − 1)); ψ = 0 at both ends, so the unknowns are the points − 2 interior values.
struct QuantumDipoleConfig {
  Index points = 16;
  Index steps = 384;  // Nt, one control value per step
  double dt = 0.05;
  double length = 2.0;

  // The HIG paper's setting: 16 points on [0, 2], 384 steps of 0.05 (T = 19.2).
  static QuantumDipoleConfig paper() { return {}; }
};

// P(u; ψ₀) = ψ(T). A complex state of M = points − 2 interior values is stored as 2M reals,
// [Re ψ₁ … Re ψ_M, Im ψ₁ … Im ψ_M]. Input: the Nt controls (u constant within each step);
// context: the initial state (required); output: the final state. Each step solves the
// tridiagonal system by the Thomas algorithm; the VJP is the exact discrete adjoint.
class QuantumDipole final : public Simulator {
 public:
  // Throws Error unless points ≥ 3, steps ≥ 1 and dt, length are finite and > 0, and unless one
  // sample's arrays fit in memory (physgrad/memory.hpp). The time loops poll for a stop request
  // (physgrad/stop.hpp) every step; the VJP checks the memory of the Nt + 1 states it keeps
  // before it allocates them.
  explicit QuantumDipole(QuantumDipoleConfig config = QuantumDipoleConfig::paper());

  std::string name() const override { return "quantum_dipole"; }
  Index input_dim() const override { return config_.steps; }
  Index output_dim() const override { return 2 * interior(); }
  Index context_dim() const override { return 2 * interior(); }
  Index interior() const { return config_.points - 2; }
  const QuantumDipoleConfig& config() const { return config_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;

 private:
  using CArray = Eigen::ArrayXXcd;
  // Diagonal of A = I + i dt/2 H(u_n) for every column (M×B).
  void step_diagonal(const Matrix& x, Index n, CArray& diag) const;
  // ψ(T); keeps ψⁿ in columns [n·B, (n + 1)·B) of `trajectory` (M × (Nt + 1)·B) when given.
  CArray integrate(const Matrix& x, const Matrix& context, CArray* trajectory) const;

  QuantumDipoleConfig config_;
  double dx_ = 0;
};

// The n-th eigenstate of −D₂ (n ≥ 1): sin(π n j/(points − 1)) at the interior points
// j = 1 … points − 2, normalised to Σ|ψ|² = 1, in the real layout above (imaginary part 0).
Vector dipole_eigenstate(Index n, Index points = 16);

}  // namespace physgrad
