#include "physgrad/optim/line_search.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

#include "physgrad/error.hpp"
#include "physgrad/optim/optimizer.hpp"

namespace physgrad {

const OptionList<LineSearchOptions>& LineSearchOptions::descriptors() {
  static const OptionList<LineSearchOptions> options = {
      rule_option("c1", &LineSearchOptions::c1, open_fraction(),
                  "sufficient decrease: φ(α) ≤ φ(0) + c1·α·φ'(0)"),
      rule_option("c2", &LineSearchOptions::c2, open_fraction(),
                  "curvature: |φ'(α)| ≤ c2·|φ'(0)|, c1 < c2"),
  };
  return options;
}

void LineSearchOptions::validate() const {
  check_options("line_search", *this);
  std::ostringstream msg;
  if (!(c2 > c1)) {
    msg << "line_search: c2 must be in (c1, 1) = (" << c1 << ", 1), got " << c2;
  } else if (max_evaluations < 1) {
    msg << "line_search: max_evaluations must be ≥ 1, got " << max_evaluations;
  } else if (!(max_step > 0)) {
    msg << "line_search: max_step must be > 0, got " << max_step;
  } else {
    return;
  }
  throw Error(msg.str());
}

namespace {

// One evaluated step length: φ(α), φ'(α) = ∇L(x + αp)ᵀp and the gradient behind it.
struct Trial {
  double step = 0;
  double value = 0;
  double slope = 0;
  Vector gradient;

  bool finite() const {
    return std::isfinite(value) && std::isfinite(slope) && all_finite(gradient);
  }
};

// Minimizer of the cubic matching φ and φ' at a and b (Nocedal & Wright eq. 3.59). Not finite
// when that cubic has no local minimizer or the data are not finite.
double cubic_minimizer(const Trial& a, const Trial& b) {
  const double d1 = a.slope + b.slope - 3 * (a.value - b.value) / (a.step - b.step);
  const double d2 = std::copysign(std::sqrt(d1 * d1 - a.slope * b.slope), b.step - a.step);
  return b.step - (b.step - a.step) * (b.slope + d2 - d1) / (b.slope - a.slope + 2 * d2);
}

class Search {
 public:
  Search(const Objective& objective, const Vector& x, const Vector& direction, double value0,
         const Vector& gradient0, const LineSearchOptions& options)
      : objective_(objective),
        x_(x),
        direction_(direction),
        options_(options),
        start_{0, value0, gradient0.dot(direction), gradient0} {
    result_.value = value0;
    result_.gradient = gradient0;
  }

  LineSearchResult run(double initial_step, double step_limit) {
    if (!std::isfinite(start_.value)) return fail("the value at the starting point is not finite");
    if (!(start_.slope < 0)) {
      std::ostringstream msg;
      msg << "not a descent direction: φ'(0) = ∇L(x)ᵀp = " << start_.slope << " is not < 0";
      return fail(msg.str());
    }
    // Algorithm 3.5: grow α until [previous, trial] brackets an acceptable step.
    Trial previous = start_;
    const double largest = std::min(options_.max_step, step_limit);
    double step = std::min(initial_step, largest);
    while (result_.evaluations < options_.max_evaluations) {
      Trial trial = evaluate(step);
      if (!trial.finite() || !sufficient_decrease(trial) ||
          (previous.step > 0 && trial.value >= previous.value)) {
        return zoom(std::move(previous), std::move(trial));
      }
      if (curvature(trial)) return accept(trial);
      if (trial.slope >= 0) return zoom(std::move(trial), std::move(previous));
      // The ray leaves the feasible region here while φ still decreases: the lowest φ on it.
      if (step >= step_limit) return accept(trial);
      if (step >= options_.max_step) {
        return fail("φ is still decreasing steeply at max_step = " + format(options_.max_step));
      }
      // Extrapolate to the minimizer of the cubic through the last two trials, but grow α by at
      // least 10% (no stalling) and at most 10× (no wild jump on a poor model).
      const double guess = cubic_minimizer(previous, trial);
      step = std::isfinite(guess) ? std::clamp(guess, 1.1 * step, 10 * step) : 10 * step;
      step = std::min(step, largest);
      previous = std::move(trial);
    }
    return out_of_evaluations();
  }

 private:
  // Algorithm 3.6. Invariants: lo satisfies sufficient decrease and has the lowest φ of all
  // such trials; φ'(lo)·(hi − lo) < 0; so an acceptable step lies between lo and hi.
  LineSearchResult zoom(Trial lo, Trial hi) {
    while (result_.evaluations < options_.max_evaluations) {
      const double a = std::min(lo.step, hi.step);
      const double b = std::max(lo.step, hi.step);
      const double margin = kSafeguard * (b - a);
      double step = cubic_minimizer(lo, hi);
      if (!(step >= a + margin && step <= b - margin)) step = 0.5 * (a + b);
      if (!(step > a && step < b)) {
        return fail("the bracket [" + format(a) + ", " + format(b) +
                    "] holds no further double; φ may be flat to rounding");
      }
      Trial trial = evaluate(step);
      if (!trial.finite() || !sufficient_decrease(trial) || trial.value >= lo.value) {
        hi = std::move(trial);
        continue;
      }
      if (curvature(trial)) return accept(trial);
      if (trial.slope * (hi.step - lo.step) >= 0) hi = std::move(lo);
      lo = std::move(trial);
    }
    return out_of_evaluations();
  }

  Trial evaluate(double step) {
    Trial trial{step, 0, 0, {}};
    trial.value = objective_.value_and_gradient(x_ + step * direction_, trial.gradient);
    trial.slope = trial.gradient.dot(direction_);
    ++result_.evaluations;
    if (!trial.finite()) ++result_.non_finite;
    if (trial.finite() && sufficient_decrease(trial) && trial.value < result_.value) {
      record(trial);
    }
    return trial;
  }

  bool sufficient_decrease(const Trial& t) const {
    return t.value <= start_.value + options_.c1 * t.step * start_.slope;
  }
  bool curvature(const Trial& t) const {
    return std::abs(t.slope) <= options_.c2 * std::abs(start_.slope);
  }

  void record(const Trial& t) {
    result_.step = t.step;
    result_.value = t.value;
    result_.gradient = t.gradient;
  }
  LineSearchResult accept(const Trial& t) {
    record(t);
    result_.success = true;
    return std::move(result_);
  }
  LineSearchResult fail(std::string message) {
    result_.message = std::move(message);
    return std::move(result_);
  }
  LineSearchResult out_of_evaluations() {
    return fail("no strong-Wolfe step within max_evaluations = " +
                std::to_string(options_.max_evaluations));
  }
  static std::string format(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
  }

  // Interpolants closer than this fraction of the bracket width to an end are replaced by the
  // midpoint, so every zoom step shrinks the bracket by at least 10%.
  static constexpr double kSafeguard = 0.1;

  const Objective& objective_;
  const Vector& x_;
  const Vector& direction_;
  const LineSearchOptions& options_;
  const Trial start_;
  LineSearchResult result_;
};

}  // namespace

LineSearchResult strong_wolfe_line_search(const Objective& objective, const Vector& x,
                                          double value0, const Vector& gradient0,
                                          const Vector& direction, double initial_step,
                                          const LineSearchOptions& options, double step_limit) {
  options.validate();
  require_positive("line search: initial_step", initial_step);
  if (!(step_limit > 0)) {
    std::ostringstream msg;
    msg << "line search: step_limit must be > 0, got " << step_limit;
    throw Error(msg.str());
  }
  const Index n = objective.dim();
  if (x.size() != n || gradient0.size() != n || direction.size() != n) {
    std::ostringstream msg;
    msg << "line search: x, gradient0 and direction have " << x.size() << ", " << gradient0.size()
        << " and " << direction.size() << " entries, expected " << n;
    throw Error(msg.str());
  }
  return Search(objective, x, direction, value0, gradient0, options).run(initial_step, step_limit);
}

}  // namespace physgrad
