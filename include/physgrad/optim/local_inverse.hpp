// Numerical local inverse P⁻¹(y; x₀): minimizes ½‖P(x; c) − y‖² from x₀, so the solution
// found is the one the descent reaches from the guess (the nearest one in the usual case).
#pragma once

#include <string>

#include "physgrad/physics/simulator.hpp"

namespace physgrad {

enum class InverseMethod {
  kAuto,         // analytic when the simulator has one, else L-BFGS
  kAnalytic,     // the simulator's own inverse()
  kLbfgs,        // L-BFGS with a strong-Wolfe line search
  kGaussNewton,  // full Gauss-Newton steps (pseudo-inverse of J)
};
std::string to_string(InverseMethod method);
// "auto", "analytic", "lbfgs" or "gn"; throws Error naming the text otherwise.
InverseMethod parse_inverse_method(const std::string& text);

struct LocalInverseOptions {
  InverseMethod method = InverseMethod::kAuto;
  // Stop once ‖P(x) − y‖ ≤ tolerance·(1 + ‖y‖).
  double tolerance = 1e-10;
  int max_iterations = 200;
};

struct LocalInverseResult {
  Vector x;
  double residual = 0;  // ‖P(x) − y‖
  int iterations = 0;
  bool converged = false;
};

// kAnalytic uses the simulator's own inverse (Error if it has none). When the misfit at x₀ is
// not finite (a NaN from the simulator or in y) the numerical inverse cannot start: the result
// is x = NaN, not converged, for the caller's numerical guard to see. Numerical trouble inside
// the numerical inverse (a non-finite Jacobian, say) throws NumericalError naming it.
LocalInverseResult local_inverse(const Simulator& simulator, const Vector& y, const Vector& x0,
                                 const Vector& context, const LocalInverseOptions& options);

}  // namespace physgrad
