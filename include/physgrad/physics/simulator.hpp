// Simulator — a differentiable map y = P(x; c) from R^n to R^m with optional local inverse.
// Batched: x, c and y hold one sample per column; vjp gives (∂P/∂x)ᵀ·gy per column.
#pragma once

#include <string>

#include "physgrad/types.hpp"

namespace physgrad {

class Simulator {
 public:
  virtual ~Simulator() = default;

  virtual std::string name() const = 0;
  virtual Index input_dim() const = 0;   // n
  virtual Index output_dim() const = 0;  // m
  // Rows of the per-sample physics context c (an initial state, say); 0 when unused.
  virtual Index context_dim() const { return 0; }

  // Y = P(X; C): X is n×B, C is context_dim()×B (0×B or empty when unused), Y is m×B.
  virtual Matrix forward_batch(const Matrix& x, const Matrix& context) const = 0;
  // GX = (∂P/∂x)ᵀ GY for every column: GY is m×B, GX is n×B.
  virtual Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const = 0;

  // J = ∂P/∂x at one sample (m×n). Default: one batched VJP with the m unit cotangents.
  virtual Matrix jacobian(const Vector& x, const Vector& context = {}) const;
  // True when jacobian() is the simulator's own (forward-mode duals, a closed form), cheaper
  // than the m VJPs of the default: the stacked Jacobian of a learning step
  // (learn/stacked_jacobian.hpp) then asks it once per sample instead of making m batched VJPs.
  virtual bool has_jacobian() const { return false; }

  // Σ_k w_k ∂²P_k/∂x² at one sample (n×n), the simulator's part of the exact Hessian of
  // L(P(x)). Default: central differences of the VJP (error O(h²)); simulators with a
  // closed form override it.
  virtual Matrix weighted_hessian(const Vector& x, const Vector& context, const Vector& w) const;

  // Local inverse P⁻¹(y; x0): the solution of P(x; c) = y nearest the guess x0.
  virtual bool has_inverse() const { return false; }
  virtual Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const;

  // Time reversal R(y; c), for a simulator whose input is an initial state and whose output the
  // state a time T later: its integrator run backwards in time (t → −t) from y, so that
  // P(R(y; c); c) ≈ y — to rounding for a time-reversible scheme (leapfrog, velocity Verlet), to
  // the scheme's truncation error otherwise. Default: none (Error).
  virtual bool has_time_reversal() const { return false; }
  virtual Vector time_reversal(const Vector& y, const Vector& context = {}) const;

  // Single-sample conveniences over the batched calls.
  Vector forward(const Vector& x, const Vector& context = {}) const;
  Vector vjp(const Vector& x, const Vector& context, const Vector& gy) const;

 protected:
  // Throws Error unless x has input_dim() rows and the context fits: context_dim() rows and one
  // column per sample, or empty unless `context_required`.
  void check_batch(const Matrix& x, const Matrix& context, const char* where,
                   bool context_required = false) const;
  // check_batch(x, context, "vjp", context_required), and that gy is output_dim() × B: the one
  // check of a vjp_batch()'s arguments ("NAME.vjp: gy is 3×4, expected 2×4").
  void check_vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy,
                       bool context_required = false) const;
};

}  // namespace physgrad
