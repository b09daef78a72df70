// Loss — a scalar objective L(y; y*) on the simulator output, with its derivatives in y
// and the Newton step in y, Δy = −(∂²L/∂y²)⁻¹ ∂L/∂y (for L2: Δy = y* − y).
#pragma once

#include <string>

#include "physgrad/types.hpp"

namespace physgrad {

class Loss {
 public:
  virtual ~Loss() = default;
  virtual std::string name() const = 0;
  virtual double value(const Vector& y, const Vector& target) const = 0;
  virtual Vector gradient(const Vector& y, const Vector& target) const = 0;  // ∂L/∂y
  virtual Matrix hessian(const Vector& y, const Vector& target) const = 0;   // ∂²L/∂y²
  // Δy = −H⁻¹ g; the default solves with a complete orthogonal decomposition.
  virtual Vector newton_step(const Vector& y, const Vector& target) const;
};

// L = (w/2)·‖y − y*‖². w = 1 is the usual ½‖·‖²; w = 2 gives the plain sum of squares.
class L2Loss final : public Loss {
 public:
  explicit L2Loss(double weight = 1.0);
  std::string name() const override { return "l2"; }
  double weight() const { return weight_; }
  double value(const Vector& y, const Vector& target) const override;
  Vector gradient(const Vector& y, const Vector& target) const override;
  Matrix hessian(const Vector& y, const Vector& target) const override;
  Vector newton_step(const Vector& y, const Vector& target) const override;

 private:
  double weight_;
};

}  // namespace physgrad
