#include "physgrad/learn/sgd.hpp"

namespace physgrad {

const OptionList<SgdOptions>& SgdOptions::descriptors() {
  static const OptionList<SgdOptions> options = {
      rule_option("lr", &SgdOptions::lr, positive(), "step size η"),
  };
  return options;
}

SgdUpdate::SgdUpdate(Options options) : options_(checked("sgd", options)) {}

void SgdUpdate::set_learning_rate(double lr) {
  Options changed = options_;
  changed.lr = lr;
  options_ = checked("sgd", changed);
}

}  // namespace physgrad
