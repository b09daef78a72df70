#include "physgrad/learn/switching.hpp"

#include <algorithm>
#include <cmath>

#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"
#include "physgrad/text.hpp"

namespace physgrad {

std::string SwitchCondition::text() const {
  if (!on_plateau()) return "after " + std::to_string(after) + " updates";
  return "on a plateau (< " + report_number(100 * fraction) + " % over " + std::to_string(window) +
         " evaluations)";
}

bool levelled_off(const std::vector<double>& losses, const SwitchCondition& condition) {
  const auto window = static_cast<std::size_t>(condition.window);
  if (!condition.on_plateau() || losses.size() <= window) return false;
  const auto recent = losses.end() - static_cast<std::ptrdiff_t>(window);
  const double before = *std::min_element(losses.begin(), recent);
  const double best_recent = *std::min_element(recent, losses.end());
  return best_recent > (1 - condition.fraction) * before;
}

SwitchingUpdate::SwitchingUpdate(std::unique_ptr<LearningUpdate> first, Index first_batch,
                                 std::unique_ptr<LearningUpdate> second, Index second_batch,
                                 SwitchCondition condition)
    : first_(std::move(first)),
      second_(std::move(second)),
      first_batch_(first_batch),
      second_batch_(second_batch),
      condition_(condition) {
  if (!first_ || !second_) throw Error("switching rule: both parts are needed");
  if (first_batch_ < 1 || second_batch_ < 1) {
    throw Error("switching rule: batch sizes must be ≥ 1, got " + std::to_string(first_batch_) +
                " and " + std::to_string(second_batch_));
  }
  if (condition_.after < 0) {
    throw Error("switching rule: 'after' must be ≥ 0, got " + std::to_string(condition_.after));
  }
  if (condition_.window < 1) {
    throw Error("switching rule: the plateau window must be ≥ 1 evaluation, got " +
                std::to_string(condition_.window));
  }
  if (!(condition_.fraction > 0 && condition_.fraction < 1)) {
    throw Error("switching rule: the plateau fraction must be in (0, 1), got " +
                report_number(condition_.fraction));
  }
}

std::string SwitchingUpdate::id() const { return first_->id() + "-" + second_->id(); }

nlohmann::json SwitchingUpdate::params() const {
  nlohmann::json params = second_->params();
  if (condition_.on_plateau()) {
    params["pretrain_window"] = condition_.window;
    params["pretrain_fraction"] = condition_.fraction;
  } else {
    params["pretrain_iterations"] = condition_.after;
  }
  params["pretrain_batch"] = first_batch_;
  const nlohmann::json first = first_->params();
  for (const auto& [key, value] : first.items()) params["pretrain_" + key] = value;
  return params;
}

void SwitchingUpdate::reset() {
  first_->reset();
  second_->reset();
  steps_ = 0;
  switched_at_ = -1;
  losses_.clear();
}

Step SwitchingUpdate::step(const BatchState& batch) {
  Step step = current().step(batch);
  ++steps_;
  if (switched_at_ < 0 && !condition_.on_plateau() && steps_ >= condition_.after) {
    switched_at_ = steps_;
    second_->reset();
  }
  return step;
}

void SwitchingUpdate::observe(const Evaluation& evaluation) {
  current().observe(evaluation);
  if (switched_at_ >= 0 || !condition_.on_plateau()) return;
  losses_.push_back(evaluation.train_loss);
  if (levelled_off(losses_, condition_)) {
    switched_at_ = steps_;
    second_->reset();
    losses_.clear();
  }
}

nlohmann::json SwitchingUpdate::state() const {
  nlohmann::json losses = nlohmann::json::array();
  for (double loss : losses_) losses.push_back(loss);
  return {{"steps", steps_},
          {"switched_at", switched_at_ >= 0 ? nlohmann::json(switched_at_) : nlohmann::json()},
          {"losses", losses},
          {"part", current().state()}};
}

void SwitchingUpdate::restore(const nlohmann::json& state, Index parameter_count) {
  reset();
  if (!state.is_object()) throw Error("checkpoint: the switching rule's state is not an object");
  steps_ = integer_from_json(state, "steps");
  if (!state.contains("switched_at")) throw Error("checkpoint field 'switched_at' is missing");
  if (!state.at("switched_at").is_null()) {
    switched_at_ = integer_from_json(state, "switched_at");
    if (switched_at_ > steps_) {
      throw Error("checkpoint field 'switched_at': " + std::to_string(switched_at_) +
                  " is after the " + std::to_string(steps_) + " updates made");
    }
  }
  const Vector losses = vector_from_json(state, "losses");
  losses_.assign(losses.data(), losses.data() + losses.size());
  if (!state.contains("part")) throw Error("checkpoint field 'part' is missing");
  current().restore(state.at("part"), parameter_count);
}

}  // namespace physgrad
