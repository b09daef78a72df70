#include "physgrad/loss/fidelity.hpp"

#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

// a = Re⟨ψ*|ψ⟩, b = Im⟨ψ*|ψ⟩ and their gradients in y.
struct Overlap {
  double a, b;
  Vector grad_a, grad_b;
};

Overlap overlap(const Vector& y, const Vector& target) {
  if (y.size() != target.size() || y.size() % 2 != 0) {
    std::ostringstream msg;
    msg << "fidelity loss: output and target must have the same even size (real and "
           "imaginary halves), got "
        << y.size() << " and " << target.size();
    throw Error(msg.str());
  }
  const Index m = y.size() / 2;
  Overlap o;
  o.grad_a = target;
  o.grad_b.resize(y.size());
  o.grad_b << -target.tail(m), target.head(m);
  o.a = o.grad_a.dot(y);
  o.b = o.grad_b.dot(y);
  return o;
}

}  // namespace

double FidelityLoss::value(const Vector& y, const Vector& target) const {
  const Overlap o = overlap(y, target);
  return 1 - o.a * o.a - o.b * o.b;
}

Vector FidelityLoss::gradient(const Vector& y, const Vector& target) const {
  const Overlap o = overlap(y, target);
  return -2 * (o.a * o.grad_a + o.b * o.grad_b);
}

Matrix FidelityLoss::hessian(const Vector& y, const Vector& target) const {
  const Overlap o = overlap(y, target);
  return -2 * (o.grad_a * o.grad_a.transpose() + o.grad_b * o.grad_b.transpose());
}

Vector FidelityLoss::newton_step(const Vector& y, const Vector& target) const {
  const Overlap o = overlap(y, target);
  const double norm2 = target.squaredNorm();
  if (norm2 == 0) return Vector::Zero(y.size());
  return -(o.a * o.grad_a + o.b * o.grad_b) / norm2;
}

}  // namespace physgrad
