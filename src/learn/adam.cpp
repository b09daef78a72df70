#include "physgrad/learn/adam.hpp"

#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"

namespace physgrad {

const OptionList<LearningAdamOptions>& LearningAdamOptions::descriptors() {
  static const OptionList<LearningAdamOptions> options = joined<LearningAdamOptions>({
      nested_options(&LearningAdamOptions::adam),
      nested_options(&LearningAdamOptions::schedule),
  });
  return options;
}

AdamUpdate::AdamUpdate(Options options)
    : options_(checked("adam", options)), moments_(options.adam), schedule_(options.schedule) {}

void AdamUpdate::reset() {
  moments_.reset();
  schedule_.reset();
}

Step AdamUpdate::step(const BatchState& batch) {
  Vector delta = moments_.update(batch.gradient);  // at the base step size η
  if (!schedule_.constant()) delta *= schedule_.rate(options_.adam.lr) / options_.adam.lr;
  schedule_.advance();
  return {std::move(delta)};
}

void AdamUpdate::set_learning_rate(double lr) {
  Options changed = options_;
  changed.adam.lr = lr;
  options_ = checked("adam", changed);
  moments_.set_learning_rate(lr);
}

nlohmann::json AdamUpdate::state() const {
  nlohmann::json state = moments_.state();
  if (!schedule_.constant()) state["schedule"] = schedule_.state();
  return state;
}

void AdamUpdate::restore(const nlohmann::json& state, Index parameter_count) {
  moments_.restore(state, parameter_count);
  schedule_.restore(schedule_.constant() ? nlohmann::json()
                                         : nlohmann::json(object_from_json(state, "schedule")));
}

}  // namespace physgrad
