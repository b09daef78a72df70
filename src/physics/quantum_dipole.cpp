#include "physgrad/physics/quantum_dipole.hpp"

#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>

#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/stop.hpp"

namespace physgrad {

namespace {

using DipoleComplex = std::complex<double>;
using CArray = Eigen::ArrayXXcd;

// Solves T z = r for every column by the Thomas algorithm, in place (r ← z). T is tridiagonal
// with diagonal `diag` (M×B) and both off-diagonals equal to `off`; `work` is M×B workspace.
void solve_tridiagonal(const CArray& diag, DipoleComplex off, CArray& r, CArray& work) {
  const Index M = diag.rows();
  work.row(0) = off / diag.row(0);
  r.row(0) /= diag.row(0);
  for (Index j = 1; j < M; ++j) {
    work.row(j) = DipoleComplex(1.0) / (diag.row(j) - off * work.row(j - 1));  // 1 / pivot
    r.row(j) = (r.row(j) - off * r.row(j - 1)) * work.row(j);
    work.row(j) *= off;
  }
  for (Index j = M - 2; j >= 0; --j) r.row(j) -= work.row(j) * r.row(j + 1);
}

// out = T v for every column, T as above.
void multiply_tridiagonal(const CArray& diag, DipoleComplex off, const CArray& v, CArray& out) {
  const Index M = diag.rows();
  out = diag * v;
  out.topRows(M - 1) += off * v.bottomRows(M - 1);
  out.bottomRows(M - 1) += off * v.topRows(M - 1);
}

}  // namespace

QuantumDipole::QuantumDipole(QuantumDipoleConfig config) : config_(config) {
  std::ostringstream msg;
  msg << "quantum_dipole: ";
  if (config_.points < 3) {
    msg << "needs at least 3 grid points, got " << config_.points;
  } else if (config_.steps < 1) {
    msg << "needs at least one step, got " << config_.steps;
  } else if (!(std::isfinite(config_.dt) && config_.dt > 0)) {
    msg << "dt must be finite and > 0, got " << config_.dt;
  } else if (!(std::isfinite(config_.length) && config_.length > 0)) {
    msg << "length must be finite and > 0, got " << config_.length;
  } else {
    // A sample: its Nt controls, its state and the solver's four complex work arrays (about
    // 12 reals per point); in double, so sizes whose 2M overflows Index are refused here too.
    require_memory(8.0 * (static_cast<double>(config_.steps) +
                          12.0 * static_cast<double>(config_.points)),
                   "quantum_dipole: " + std::to_string(config_.points) + " points, " +
                       std::to_string(config_.steps) +
                       " steps (one sample's controls, state and work arrays)");
    dx_ = config_.length / static_cast<double>(config_.points - 1);
    return;
  }
  throw Error(msg.str());
}

void QuantumDipole::step_diagonal(const Matrix& x, Index n, CArray& diag) const {
  // A_jj = 1 + i dt/2 (2/dx² + u x_j) with x_j = j·dx.
  const double dt = config_.dt;
  for (Index b = 0; b < diag.cols(); ++b) {
    for (Index j = 0; j < diag.rows(); ++j) {
      const double xj = static_cast<double>(j + 1) * dx_;
      diag(j, b) = DipoleComplex(1.0, dt / (dx_ * dx_) + 0.5 * dt * x(n, b) * xj);
    }
  }
}

QuantumDipole::CArray QuantumDipole::integrate(const Matrix& x, const Matrix& context,
                                               CArray* trajectory) const {
  const Index M = interior(), B = x.cols();
  const DipoleComplex off(0.0, -0.5 * config_.dt / (dx_ * dx_));  // A_{j,j±1}
  CArray psi(M, B), diag(M, B), conj_diag(M, B), r(M, B), work(M, B);
  psi.real() = context.topRows(M).array();
  psi.imag() = context.bottomRows(M).array();
  for (Index n = 0; n < config_.steps; ++n) {
    throw_if_stop_requested("quantum_dipole");
    if (trajectory) trajectory->middleCols(n * B, B) = psi;
    step_diagonal(x, n, diag);
    conj_diag = diag.conjugate();
    multiply_tridiagonal(conj_diag, std::conj(off), psi, r);  // r = conj(A) ψⁿ
    solve_tridiagonal(diag, off, r, work);
    psi.swap(r);
  }
  if (trajectory) trajectory->middleCols(config_.steps * B, B) = psi;
  return psi;
}

Matrix QuantumDipole::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward", true);
  const CArray psi = integrate(x, context, nullptr);
  Matrix y(output_dim(), x.cols());
  y.topRows(interior()) = psi.real().matrix();
  y.bottomRows(interior()) = psi.imag().matrix();
  return y;
}

Matrix QuantumDipole::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_vjp_batch(x, context, gy, true);
  const Index M = interior(), B = x.cols();
  require_memory(16.0 * static_cast<double>(M) * (static_cast<double>(config_.steps) + 1) *
                     static_cast<double>(B),
                 name() + ".vjp: the states of " + std::to_string(M) + " points over " +
                     std::to_string(config_.steps) + " steps for " + std::to_string(B) +
                     " samples");
  CArray trajectory(M, (config_.steps + 1) * B);
  integrate(x, context, &trajectory);

  // The real pairing ⟨gy, δy⟩ is Re Σ conj(λ_j) δψ_j with λ = gy_re + i gy_im. A is complex
  // symmetric, so for ψⁿ⁺¹ = A⁻¹ conj(A) ψⁿ: μ solves conj(A) μ = λⁿ⁺¹, λⁿ = A μ, and
  // ∂A/∂u = i dt/2 diag(x) = −∂conj(A)/∂u gives ∂/∂u_n = dt/2 Σ_j x_j Im(conj(μ_j)(ψⁿ_j + ψⁿ⁺¹_j)).
  const double dt = config_.dt;
  const DipoleComplex off(0.0, -0.5 * dt / (dx_ * dx_));
  CArray lambda(M, B), diag(M, B), conj_diag(M, B), r(M, B), work(M, B);
  lambda.real() = gy.topRows(M).array();
  lambda.imag() = gy.bottomRows(M).array();
  Matrix gx(config_.steps, B);
  for (Index n = config_.steps - 1; n >= 0; --n) {
    throw_if_stop_requested("quantum_dipole.vjp");
    step_diagonal(x, n, diag);
    conj_diag = diag.conjugate();
    solve_tridiagonal(conj_diag, std::conj(off), lambda, work);  // λ ← μ
    for (Index b = 0; b < B; ++b) {
      double g = 0;
      for (Index j = 0; j < M; ++j) {
        const DipoleComplex sum = trajectory(j, n * B + b) + trajectory(j, (n + 1) * B + b);
        g += static_cast<double>(j + 1) * dx_ * std::imag(std::conj(lambda(j, b)) * sum);
      }
      gx(n, b) = 0.5 * dt * g;
    }
    multiply_tridiagonal(diag, off, lambda, r);
    lambda.swap(r);
  }
  return gx;
}

Vector dipole_eigenstate(Index n, Index points) {
  if (points < 3 || n < 1 || n > points - 2) {
    std::ostringstream msg;
    msg << "dipole_eigenstate: need points ≥ 3 and 1 ≤ n ≤ points − 2, got n " << n
        << ", points " << points;
    throw Error(msg.str());
  }
  const Index M = points - 2;
  Vector psi = Vector::Zero(2 * M);
  for (Index j = 0; j < M; ++j) {
    psi(j) = std::sin(std::numbers::pi * static_cast<double>(n * (j + 1)) /
                      static_cast<double>(points - 1));
  }
  return psi / psi.norm();
}

}  // namespace physgrad
