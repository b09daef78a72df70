#include "physgrad/optim/gradient_descent.hpp"

namespace physgrad {

GradientDescent::GradientDescent(Options options) : options_(options) {
  require_positive("gd: lr", options_.lr);
}

Step GradientDescent::step(const Objective& objective, const Vector& x) {
  return {-options_.lr * objective.gradient(x), Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
