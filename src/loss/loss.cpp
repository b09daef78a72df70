#include "physgrad/loss/loss.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {
void check_target_shape(const Vector& y, const Vector& target) {
  if (y.size() != target.size()) {
    std::ostringstream msg;
    msg << "loss: output has " << y.size() << " entries but the target has " << target.size();
    throw Error(msg.str());
  }
}
}  // namespace

Vector Loss::newton_step(const Vector& y, const Vector& target) const {
  return -hessian(y, target).completeOrthogonalDecomposition().solve(gradient(y, target));
}

L2Loss::L2Loss(double weight) : weight_(weight) {
  if (!(std::isfinite(weight) && weight > 0)) {
    std::ostringstream msg;
    msg << "L2Loss: weight must be finite and > 0, got " << weight;
    throw Error(msg.str());
  }
}

double L2Loss::value(const Vector& y, const Vector& target) const {
  check_target_shape(y, target);
  return 0.5 * weight_ * (y - target).squaredNorm();
}

Vector L2Loss::gradient(const Vector& y, const Vector& target) const {
  check_target_shape(y, target);
  return weight_ * (y - target);
}

Matrix L2Loss::hessian(const Vector& y, const Vector& target) const {
  check_target_shape(y, target);
  return weight_ * Matrix::Identity(y.size(), y.size());
}

Vector L2Loss::newton_step(const Vector& y, const Vector& target) const {
  check_target_shape(y, target);
  return target - y;
}

}  // namespace physgrad
