// CoupledOscillators — a chain of N controlled oscillators integrated with classic RK4.
// x_i' = v_i, v_i' = −x_i + Σ_nb [k₁(x_nb − x_i) + k₃(x_nb − x_i)³] + c·u(t)·[i = N].
#pragma once

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// What the simulator's input x is: the controls (context: the initial state), or the initial
// state (context: the controls, or none for zero controls).
enum class OscillatorInput { kControls, kInitialState };

// Parameters of the oscillator chain. Neighbours of i are i ± 1 with free ends (a missing
// neighbour contributes nothing); the control u acts on the last oscillator only.
struct OscillatorConfig {
  Index oscillators = 2;         // N
  Index steps = 96;              // Nt, one control value per step
  double dt = 0.125;             // step size; T = Nt·dt
  double linear_coupling = 0.0;  // k₁
  double cubic_coupling = 1.0;   // k₃
  double control_factor = 3.0;   // c
  OscillatorInput input = OscillatorInput::kControls;

  // Nonlinear oscillators of the HIG paper: N 2, Nt 96, dt 0.125, k₁ 0, k₃ 1, c 3.
  static OscillatorConfig paper() { return {}; }
  // Linear oscillators of the HIG book chapter: N 2, Nt 24, dt 0.5, k₁ 0.2, k₃ 0, c 1.
  static OscillatorConfig book() { return {2, 24, 0.5, 0.2, 0.0, 1.0}; }
};

// P(u; s₀) = s(T): input the Nt controls (u held constant within each RK4 step), context the
// initial state s₀ = (x_1..x_N, v_1..v_N) (required), output the final state in the same
// layout. With OscillatorInput::kInitialState, P(s₀; u) = s(T) instead: input s₀, context the
// controls (optional: none means u = 0). The VJP is the exact discrete adjoint of the RK4 scheme.
//
// Time reversal (kInitialState only): RK4 with step −dt from s(T) through the controls in
// reverse order. RK4 is not time-reversible, so P(R(y)) = y only up to the scheme's truncation
// error (measured in tests/time_reversal_test.cpp).
class CoupledOscillators final : public Simulator {
 public:
  // Throws Error unless N ≥ 1, Nt ≥ 1, dt > 0 and every coefficient is finite, and unless one
  // sample's arrays fit in memory (physgrad/memory.hpp). The time loops (forward, VJP, time
  // reversal) poll for a stop request (physgrad/stop.hpp) every step; the VJP checks the memory
  // of the 4·Nt stage positions it keeps before it allocates them.
  explicit CoupledOscillators(OscillatorConfig config = OscillatorConfig::paper());

  std::string name() const override { return "coupled_oscillators"; }
  Index input_dim() const override { return controls_in() ? config_.steps : state_dim(); }
  Index output_dim() const override { return state_dim(); }
  Index context_dim() const override { return controls_in() ? state_dim() : config_.steps; }
  const OscillatorConfig& config() const { return config_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  bool has_time_reversal() const override { return !controls_in(); }
  Vector time_reversal(const Vector& y, const Vector& context = {}) const override;

 private:
  using Array = Eigen::ArrayXXd;
  bool controls_in() const { return config_.input == OscillatorInput::kControls; }
  Index state_dim() const { return 2 * config_.oscillators; }
  // The controls (Nt × B) and initial states (2N × B) of a batch, whichever the input is.
  void split(const Matrix& x, const Matrix& context, Matrix& controls, Matrix& initial) const;
  struct Workspace {
    Array z, k, slope;
  };
  // One RK4 step of size h from s with control row n; stores the positions of its four stage
  // states in columns [4n·B, (4n + 4)·B) of `stage_positions` when it is given.
  void rk4_step(Array& s, const Matrix& controls, Index n, double h, Workspace& w,
                Array* stage_positions) const;
  // s(T) for every column; stores the positions of the four RK4 stage states of step n in
  // columns [4n·B, (4n + 4)·B) of `stage_positions` (N × 4·Nt·B) when it is given.
  Array integrate(const Matrix& controls, const Matrix& initial, Array* stage_positions) const;
  // k = f(z, u_n) for every column, u_n = row n of x.
  void rhs(const Array& z, const Matrix& x, Index n, Array& k) const;
  // out = (∂f/∂z)ᵀ a for every column; f depends on z only through the positions `pos`.
  void rhs_adjoint(const Eigen::Ref<const Array>& pos, const Array& a, Array& out) const;

  OscillatorConfig config_;
};

}  // namespace physgrad
