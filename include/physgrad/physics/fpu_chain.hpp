// FpuChain — a Fermi–Pasta–Ulam–Tsingou β chain of N unit masses between fixed walls, advanced
// by velocity Verlet: q̈ᵢ = F(qᵢ₊₁ − qᵢ) − F(qᵢ − qᵢ₋₁), F(r) = r + β r³, q₀ = q_{N+1} = 0.
#pragma once

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

struct FpuChainConfig {
  Index masses = 8;  // N ≥ 1
  Index steps = 100;  // Nt ≥ 1 velocity-Verlet steps; T = Nt·dt
  double dt = 0.1;    // > 0
  double beta = 1.0;  // β of the quartic bond energy r²/2 + β r⁴/4, finite
};

// P(s₀) = s(T): input and output the state (q₁..q_N, p₁..p_N); no context. One step:
// p ← p + (dt/2) a(q), q ← q + dt p, p ← p + (dt/2) a(q). The VJP is the exact discrete adjoint
// of these steps; the bond Hessian is symmetric, so a(q)'s Jacobian is its own transpose.
//
// Velocity Verlet is time-reversible: flipping the momenta, taking the same Nt steps and
// flipping them back retraces the trajectory, so the time reversal R(y) is the exact inverse
// of P up to rounding (P(R(y)) = y to ~1e-14 relative for the default chain, measured in
// tests/time_reversal_test.cpp).
class FpuChain final : public Simulator {
 public:
  // Throws Error unless N ≥ 1, Nt ≥ 1, dt finite and > 0, β finite, and unless one state and
  // its work arrays fit in memory (physgrad/memory.hpp). The time loops poll for a stop request
  // (physgrad/stop.hpp) every step; the VJP checks the memory of the Nt + 1 positions it keeps
  // before it allocates them.
  explicit FpuChain(FpuChainConfig config = {});

  std::string name() const override { return "fpu_chain"; }
  Index input_dim() const override { return 2 * config_.masses; }
  Index output_dim() const override { return 2 * config_.masses; }
  const FpuChainConfig& config() const { return config_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  bool has_time_reversal() const override { return true; }
  Vector time_reversal(const Vector& y, const Vector& context = {}) const override;

 private:
  using Array = Eigen::ArrayXXd;
  // a(q) for every column (q is N × B).
  Array acceleration(const Array& q) const;
  // (∂a/∂q) λ at q for every column.
  Array acceleration_jvp(const Array& q, const Array& lambda) const;
  // Nt steps from the state s (2N × B); the positions before each step and the final ones in
  // columns [n·B, (n + 1)·B) of `positions` (N × (Nt + 1)·B) when it is given.
  Array integrate(Array s, Array* positions) const;

  FpuChainConfig config_;
};

}  // namespace physgrad
