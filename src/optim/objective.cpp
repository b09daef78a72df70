#include "physgrad/optim/objective.hpp"

#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

Objective::Objective(const Simulator& simulator, const Loss& loss, Vector target, Vector context)
    : simulator_(&simulator), loss_(&loss), target_(std::move(target)), context_(std::move(context)) {
  if (target_.size() != simulator.output_dim()) {
    std::ostringstream msg;
    msg << "objective: target has " << target_.size() << " entries, simulator '"
        << simulator.name() << "' has output_dim " << simulator.output_dim();
    throw Error(msg.str());
  }
  if (context_.size() != 0 && context_.size() != simulator.context_dim()) {
    std::ostringstream msg;
    msg << "objective: context has " << context_.size() << " entries, simulator '"
        << simulator.name() << "' expects " << simulator.context_dim();
    throw Error(msg.str());
  }
}

void Objective::check_x(const Vector& x) const {
  if (x.size() != dim()) {
    std::ostringstream msg;
    msg << "objective: x has " << x.size() << " entries, expected " << dim();
    throw Error(msg.str());
  }
}

Vector Objective::output(const Vector& x) const {
  check_x(x);
  return simulator_->forward(x, context_);
}

double Objective::value(const Vector& x) const { return loss_->value(output(x), target_); }

Vector Objective::gradient(const Vector& x) const {
  Vector g;
  value_and_gradient(x, g);
  return g;
}

double Objective::value_and_gradient(const Vector& x, Vector& gradient) const {
  const Vector y = output(x);
  gradient = simulator_->vjp(x, context_, loss_->gradient(y, target_));
  return loss_->value(y, target_);
}

Matrix Objective::jacobian(const Vector& x) const {
  check_x(x);
  return simulator_->jacobian(x, context_);
}

Matrix Objective::hessian(const Vector& x) const {
  const Vector y = output(x);
  const Matrix j = simulator_->jacobian(x, context_);
  const Matrix gauss_newton = j.transpose() * loss_->hessian(y, target_) * j;
  return gauss_newton + simulator_->weighted_hessian(x, context_, loss_->gradient(y, target_));
}

CheckedObjective::CheckedObjective(const Objective& objective)
    : given_(&objective),
      simulator_(&CheckedSimulator::around(objective.simulator(), own_simulator_)) {
  if (own_simulator_) {
    own_objective_.emplace(*simulator_, objective.loss(), objective.target(), objective.context());
  }
}

}  // namespace physgrad
