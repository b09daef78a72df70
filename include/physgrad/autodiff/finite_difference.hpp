// Finite-difference checks of derivatives: central differences (f(x+h) − f(x−h))/2h, error
// O(h²), used to verify a simulator's Jacobian, VJP, second derivatives and local inverse.
#pragma once

#include <functional>
#include <string>

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

// ∂f/∂x at x by central differences with step h·max(1, |xᵢ|) per component. Throws Error when f
// returns vectors of different sizes.
Matrix finite_difference_jacobian(const std::function<Vector(const Vector&)>& f, const Vector& x,
                                  double h = 1e-6);

struct DerivativeCheck {
  double jacobian_error = 0;  // max |J − J_fd| / max(1, max|J_fd|)
  double vjp_error = 0;       // |vᵀ(J_fd) − vjp(v)| relative, for a fixed pseudo-random v
  double hessian_error = 0;   // weighted_hessian vs differences of the VJP, relative
  bool passed = false;        // every error ≤ tolerance
  std::string report() const;
};

// Compares jacobian(), vjp() and weighted_hessian() of `simulator` at (x, c) with central
// differences of forward() and vjp(). `tolerance` bounds each relative error. The simulator is
// called through a CheckedSimulator: a result of the wrong shape is an Error naming it.
DerivativeCheck check_derivatives(const Simulator& simulator, const Vector& x,
                                  const Vector& context = {}, double tolerance = 1e-6);

// ‖P(P⁻¹(y; x0)) − y‖ / max(1, ‖y‖): how well the simulator's inverse reproduces y.
double inverse_residual(const Simulator& simulator, const Vector& y, const Vector& x0,
                        const Vector& context = {});

}  // namespace physgrad
