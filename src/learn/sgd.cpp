#include "physgrad/learn/sgd.hpp"

#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

SgdUpdate::SgdUpdate(Options options) : options_(options) {
  require_positive("sgd: lr", options_.lr);
}

void SgdUpdate::set_learning_rate(double lr) {
  require_positive("sgd: lr", lr);
  options_.lr = lr;
}

}  // namespace physgrad
