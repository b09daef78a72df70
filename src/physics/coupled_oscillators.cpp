#include "physgrad/physics/coupled_oscillators.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/stop.hpp"

namespace physgrad {

CoupledOscillators::CoupledOscillators(OscillatorConfig config) : config_(config) {
  std::ostringstream msg;
  msg << "coupled_oscillators: ";
  if (config_.oscillators < 1) {
    msg << "needs at least one oscillator, got " << config_.oscillators;
  } else if (config_.steps < 1) {
    msg << "needs at least one step, got " << config_.steps;
  } else if (!(std::isfinite(config_.dt) && config_.dt > 0)) {
    msg << "dt must be finite and > 0, got " << config_.dt;
  } else if (!std::isfinite(config_.linear_coupling) || !std::isfinite(config_.cubic_coupling) ||
             !std::isfinite(config_.control_factor)) {
    msg << "coefficients must be finite, got linear " << config_.linear_coupling << ", cubic "
        << config_.cubic_coupling << ", control " << config_.control_factor;
  } else {
    // A sample: its Nt controls (and a copy), its state and RK4's work arrays (about 10N); in
    // double, so sizes whose 2N or Nt overflow Index are refused here too.
    const double values = 2.0 * static_cast<double>(config_.steps) +
                          10.0 * static_cast<double>(config_.oscillators);
    require_memory(8.0 * values, "coupled_oscillators: " + std::to_string(config_.oscillators) +
                                     " oscillators, " + std::to_string(config_.steps) +
                                     " steps (one sample's controls, state and work arrays)");
    return;
  }
  throw Error(msg.str());
}

void CoupledOscillators::rhs(const Array& z, const Matrix& x, Index n, Array& k) const {
  const Index N = config_.oscillators;
  k.topRows(N) = z.bottomRows(N);
  k.bottomRows(N) = -z.topRows(N);
  if (N > 1) {
    // d_i = x_{i+1} − x_i pushes oscillator i by g(d_i) and oscillator i+1 by −g(d_i).
    const auto d = z.middleRows(1, N - 1) - z.topRows(N - 1);
    const auto g = config_.linear_coupling * d + config_.cubic_coupling * d.cube();
    k.middleRows(N, N - 1) += g;
    k.bottomRows(N - 1) -= g;
  }
  k.row(2 * N - 1) += config_.control_factor * x.row(n).array();
}

void CoupledOscillators::rhs_adjoint(const Eigen::Ref<const Array>& pos, const Array& a,
                                     Array& out) const {
  const Index N = config_.oscillators;
  out.topRows(N) = -a.bottomRows(N);
  out.bottomRows(N) = a.topRows(N);
  if (N > 1) {
    // w_i = g'(d_i)·(a_{v_i} − a_{v_{i+1}}) flows back into x_{i+1} (+) and x_i (−).
    const auto d = pos.bottomRows(N - 1) - pos.topRows(N - 1);
    const auto w = (config_.linear_coupling + 3 * config_.cubic_coupling * d.square()) *
                   (a.middleRows(N, N - 1) - a.bottomRows(N - 1));
    out.middleRows(1, N - 1) += w;
    out.topRows(N - 1) -= w;
  }
}

void CoupledOscillators::split(const Matrix& x, const Matrix& context, Matrix& controls,
                               Matrix& initial) const {
  if (controls_in()) {
    controls = x;
    initial = context;
  } else {
    controls = context.size() == 0 ? Matrix(Matrix::Zero(config_.steps, x.cols())) : context;
    initial = x;
  }
}

void CoupledOscillators::rk4_step(Array& s, const Matrix& controls, Index n, double h,
                                  Workspace& w, Array* stage_positions) const {
  const Index N = config_.oscillators, B = s.cols();
  Array &z = w.z, &k = w.k, &slope = w.slope;
  z.resize(2 * N, B);
  k.resize(2 * N, B);
  slope.resize(2 * N, B);
  const auto store = [&](Index stage, const Array& state) {
    if (stage_positions) stage_positions->middleCols((4 * n + stage) * B, B) = state.topRows(N);
  };
  store(0, s);
  rhs(s, controls, n, k);
  slope = k;
  z = s + 0.5 * h * k;
  store(1, z);
  rhs(z, controls, n, k);
  slope += 2 * k;
  z = s + 0.5 * h * k;
  store(2, z);
  rhs(z, controls, n, k);
  slope += 2 * k;
  z = s + h * k;
  store(3, z);
  rhs(z, controls, n, k);
  slope += k;
  s += (h / 6) * slope;
}

CoupledOscillators::Array CoupledOscillators::integrate(const Matrix& controls,
                                                        const Matrix& initial,
                                                        Array* stage_positions) const {
  Array s = initial.array();
  Workspace w;
  for (Index n = 0; n < config_.steps; ++n) {
    throw_if_stop_requested("coupled_oscillators");
    rk4_step(s, controls, n, config_.dt, w, stage_positions);
  }
  return s;
}

Matrix CoupledOscillators::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward", controls_in());
  Matrix controls, initial;
  split(x, context, controls, initial);
  return integrate(controls, initial, nullptr).matrix();
}

Vector CoupledOscillators::time_reversal(const Vector& y, const Vector& context) const {
  if (controls_in()) {
    throw Error(name() + ": time reversal needs the initial state as input "
                "(OscillatorInput::kInitialState)");
  }
  check_batch(y, context, "time_reversal");  // y, like x, is a state
  Matrix controls, state;
  split(y, context, controls, state);
  Array s = state.array();
  Workspace w;
  for (Index n = config_.steps - 1; n >= 0; --n) {
    throw_if_stop_requested("coupled_oscillators.time_reversal");
    rk4_step(s, controls, n, -config_.dt, w, nullptr);
  }
  return s.matrix();
}

Matrix CoupledOscillators::vjp_batch(const Matrix& x, const Matrix& context,
                                     const Matrix& gy) const {
  check_vjp_batch(x, context, gy, controls_in());
  const Index N = config_.oscillators, B = x.cols(), last = 2 * N - 1;
  require_memory(8.0 * static_cast<double>(N) * 4 * static_cast<double>(config_.steps) *
                     static_cast<double>(B),
                 name() + ".vjp: the stage positions of " + std::to_string(N) +
                     " oscillators over " + std::to_string(config_.steps) + " steps for " +
                     std::to_string(B) + " samples");
  Matrix controls, initial;
  split(x, context, controls, initial);
  Array positions(N, 4 * config_.steps * B);
  integrate(controls, initial, &positions);

  // Reverse sweep. s' = s + dt/6 (k₁ + 2k₂ + 2k₃ + k₄) with k_i = f(z_i, u), z₁ = s,
  // z₂ = s + dt/2 k₁, z₃ = s + dt/2 k₂, z₄ = s + dt k₃. `a` is the adjoint of the current k_i,
  // `za` = (∂f/∂z_i)ᵀ a that of z_i; ∂f/∂u = c·e_{v_N}, so u_n collects c·a[v_N] per stage.
  const double dt = config_.dt;
  const auto stage = [&](Index n, Index i) { return positions.middleCols((4 * n + i) * B, B); };
  Array lambda = gy.array(), next(2 * N, B), a(2 * N, B), za(2 * N, B);
  Matrix gx(config_.steps, B);
  for (Index n = config_.steps - 1; n >= 0; --n) {
    throw_if_stop_requested("coupled_oscillators.vjp");
    a = (dt / 6) * lambda;
    gx.row(n) = a.row(last).matrix();
    rhs_adjoint(stage(n, 3), a, za);
    next = lambda + za;
    a = (dt / 3) * lambda + dt * za;
    gx.row(n) += a.row(last).matrix();
    rhs_adjoint(stage(n, 2), a, za);
    next += za;
    a = (dt / 3) * lambda + (dt / 2) * za;
    gx.row(n) += a.row(last).matrix();
    rhs_adjoint(stage(n, 1), a, za);
    next += za;
    a = (dt / 6) * lambda + (dt / 2) * za;
    gx.row(n) += a.row(last).matrix();
    rhs_adjoint(stage(n, 0), a, za);
    next += za;
    lambda.swap(next);
    gx.row(n) *= config_.control_factor;
  }
  // After the sweep λ is the adjoint of the initial state.
  return controls_in() ? gx : Matrix(lambda.matrix());
}

}  // namespace physgrad
