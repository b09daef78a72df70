#include "physgrad/optim/adam.hpp"

#include <cmath>
#include <sstream>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/io/serialize.hpp"

namespace physgrad {

const OptionList<AdamOptions>& AdamOptions::descriptors() {
  static const OptionList<AdamOptions> options = {
      rule_option("lr", &AdamOptions::lr, positive(), "step size η"),
      rule_option("beta1", &AdamOptions::beta1, fraction(), "decay β₁ of the first moment"),
      rule_option("beta2", &AdamOptions::beta2, fraction(), "decay β₂ of the second moment"),
      rule_option("epsilon", &AdamOptions::epsilon, positive(), "ε added to √v̂"),
  };
  return options;
}

AdamState::AdamState(Options options) : options_(checked("adam", options)) {}

void AdamState::reset() {
  m_.resize(0);
  v_.resize(0);
  t_ = 0;
}

Vector AdamState::update(const Vector& gradient) {
  if (m_.size() != gradient.size()) {
    m_ = Vector::Zero(gradient.size());
    v_ = Vector::Zero(gradient.size());
    t_ = 0;
  }
  // A gradient whose square overflows would make v infinite and the step silently zero: refuse
  // it, leaving the moments as they were.
  Vector m = options_.beta1 * m_ + (1 - options_.beta1) * gradient;
  Vector v = options_.beta2 * v_ + (1 - options_.beta2) * gradient.cwiseAbs2();
  if (!all_finite(m) || !all_finite(v)) {
    std::ostringstream msg;
    msg << "Adam's moment estimates are not finite (largest |gradient| entry "
        << gradient.cwiseAbs().maxCoeff() << ")";
    throw NumericalError(msg.str());
  }
  ++t_;
  m_ = std::move(m);
  v_ = std::move(v);
  const double m_correction = 1 - std::pow(options_.beta1, static_cast<double>(t_));
  const double v_correction = 1 - std::pow(options_.beta2, static_cast<double>(t_));
  return -options_.lr * (m_ / m_correction).array() /
         ((v_ / v_correction).array().sqrt() + options_.epsilon);
}

nlohmann::json AdamState::state() const {
  return {{"t", t_}, {"m", vector_to_json(m_)}, {"v", vector_to_json(v_)}};
}

void AdamState::restore(const nlohmann::json& state, Index size) {
  const long long t = integer_from_json(state, "t");
  // Before the first update the moments are empty; afterwards they have one entry per θ.
  const Index moments = t == 0 ? 0 : size;
  Vector m = vector_from_json(state, "m", moments), v = vector_from_json(state, "v", moments);
  if ((v.array() < 0).any()) throw Error("checkpoint field 'v': negative second moment");
  m_ = std::move(m);
  v_ = std::move(v);
  t_ = t;
}

nlohmann::json AdamState::params() const { return option_values(options_); }

void AdamState::set_learning_rate(double lr) {
  Options changed = options_;
  changed.lr = lr;
  options_ = checked("adam", changed);
}

Step Adam::propose(const Objective& objective, const Vector& x, const Domain& domain) {
  // The moments live in z: Δz = Adam(D g), Δx = D Δz, projected onto the box.
  const Vector s = domain.scale(x.size());
  const Vector dz = state_.update(s.cwiseProduct(objective.gradient(x)));
  return {domain.feasible_step(x, s.cwiseProduct(dz)), Step::Status::kOk, {}, 1};
}

}  // namespace physgrad
