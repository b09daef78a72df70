// Objective — the direct-optimization problem L(x) = Loss(P(x; c), y*) for one sample,
// with g = Jᵀ ∂L/∂y and the exact Hessian H = Jᵀ (∂²L/∂y²) J + Σ_k (∂L/∂y_k) ∂²P_k/∂x².
#pragma once

#include <optional>

#include "physgrad/loss/loss.hpp"
#include "physgrad/physics/checked_simulator.hpp"

namespace physgrad {

// Holds references: the simulator and loss must outlive the Objective.
class Objective {
 public:
  Objective(const Simulator& simulator, const Loss& loss, Vector target, Vector context = {});

  Index dim() const { return simulator_->input_dim(); }
  const Simulator& simulator() const { return *simulator_; }
  const Loss& loss() const { return *loss_; }
  const Vector& target() const { return target_; }
  const Vector& context() const { return context_; }

  Vector output(const Vector& x) const;  // y = P(x; c)
  double value(const Vector& x) const;   // L(x)
  Vector gradient(const Vector& x) const;
  double value_and_gradient(const Vector& x, Vector& gradient) const;
  Matrix jacobian(const Vector& x) const;  // ∂P/∂x
  Matrix hessian(const Vector& x) const;   // exact ∂²L/∂x²

 private:
  void check_x(const Vector& x) const;

  const Simulator* simulator_;
  const Loss* loss_;
  Vector target_;
  Vector context_;
};

// An Objective whose simulator is a CheckedSimulator: `objective` itself when its simulator is
// one already, else a copy around one of its own (the same loss, target and context). The
// drivers hand the rules only such objectives.
class CheckedObjective {
 public:
  explicit CheckedObjective(const Objective& objective);
  CheckedObjective(const CheckedObjective&) = delete;
  CheckedObjective& operator=(const CheckedObjective&) = delete;

  const Objective& objective() const { return own_objective_ ? *own_objective_ : *given_; }
  const CheckedSimulator& simulator() const { return *simulator_; }

 private:
  const Objective* given_;
  std::optional<CheckedSimulator> own_simulator_;
  const CheckedSimulator* simulator_;
  std::optional<Objective> own_objective_;
};

}  // namespace physgrad
