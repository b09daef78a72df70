// The y-space step of the inversion rules: Δy = η·(Newton step of the loss L in y) at y, toward
// the target y* (for L2: Δy = η(y* − y)); ig inverts it, pg and sip reach y + Δy by P⁻¹.
#pragma once

#include "physgrad/loss/loss.hpp"
#include "physgrad/types.hpp"

namespace physgrad {

// η·loss.newton_step(y, target).
Vector y_step(const Loss& loss, const Vector& y, const Vector& target, double lr);

}  // namespace physgrad
