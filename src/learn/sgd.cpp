#include "physgrad/learn/sgd.hpp"

namespace physgrad {

const OptionList<SgdOptions>& SgdOptions::descriptors() {
  static const OptionList<SgdOptions> options = joined<SgdOptions>({
      {rule_option("lr", &SgdOptions::lr, positive(), "step size η")},
      nested_options(&SgdOptions::schedule),
  });
  return options;
}

SgdUpdate::SgdUpdate(Options options)
    : options_(checked("sgd", options)), schedule_(options.schedule) {}

Step SgdUpdate::step(const BatchState& batch) {
  Step step{-schedule_.rate(options_.lr) * batch.gradient};
  schedule_.advance();
  return step;
}

void SgdUpdate::set_learning_rate(double lr) {
  Options changed = options_;
  changed.lr = lr;
  options_ = checked("sgd", changed);
}

}  // namespace physgrad
