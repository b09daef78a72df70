#include "physgrad/inversion/y_step.hpp"

namespace physgrad {

Vector y_step(const Loss& loss, const Vector& y, const Vector& target, double lr) {
  return lr * loss.newton_step(y, target);
}

}  // namespace physgrad
