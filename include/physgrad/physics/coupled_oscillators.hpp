// CoupledOscillators — a chain of N controlled oscillators integrated with classic RK4.
// x_i' = v_i, v_i' = −x_i + Σ_nb [k₁(x_nb − x_i) + k₃(x_nb − x_i)³] + c·u(t)·[i = N].
#pragma once

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// Parameters of the oscillator chain. Neighbours of i are i ± 1 with free ends (a missing
// neighbour contributes nothing); the control u acts on the last oscillator only.
struct OscillatorConfig {
  Index oscillators = 2;         // N
  Index steps = 96;              // Nt, one control value per step
  double dt = 0.125;             // step size; T = Nt·dt
  double linear_coupling = 0.0;  // k₁
  double cubic_coupling = 1.0;   // k₃
  double control_factor = 3.0;   // c

  // Nonlinear oscillators of the HIG paper: N 2, Nt 96, dt 0.125, k₁ 0, k₃ 1, c 3.
  static OscillatorConfig paper() { return {}; }
  // Linear oscillators of the HIG book chapter: N 2, Nt 24, dt 0.5, k₁ 0.2, k₃ 0, c 1.
  static OscillatorConfig book() { return {2, 24, 0.5, 0.2, 0.0, 1.0}; }
};

// P(u; s₀) = s(T): input the Nt controls (u held constant within each RK4 step), context the
// initial state s₀ = (x_1..x_N, v_1..v_N) (required), output the final state in the same
// layout. The VJP is the exact discrete adjoint of the RK4 scheme.
class CoupledOscillators final : public Simulator {
 public:
  // Throws Error unless N ≥ 1, Nt ≥ 1, dt > 0 and every coefficient is finite.
  explicit CoupledOscillators(OscillatorConfig config = OscillatorConfig::paper());

  std::string name() const override { return "coupled_oscillators"; }
  Index input_dim() const override { return config_.steps; }
  Index output_dim() const override { return 2 * config_.oscillators; }
  Index context_dim() const override { return 2 * config_.oscillators; }
  const OscillatorConfig& config() const { return config_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;

 private:
  using Array = Eigen::ArrayXXd;
  // s(T) for every column; stores the positions of the four RK4 stage states of step n in
  // columns [4n·B, (4n + 4)·B) of `stage_positions` (N × 4·Nt·B) when it is given.
  Array integrate(const Matrix& x, const Matrix& context, Array* stage_positions) const;
  // k = f(z, u_n) for every column, u_n = row n of x.
  void rhs(const Array& z, const Matrix& x, Index n, Array& k) const;
  // out = (∂f/∂z)ᵀ a for every column; f depends on z only through the positions `pos`.
  void rhs_adjoint(const Eigen::Ref<const Array>& pos, const Array& a, Array& out) const;

  OscillatorConfig config_;
};

}  // namespace physgrad
