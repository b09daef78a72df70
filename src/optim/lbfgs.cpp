#include "physgrad/optim/lbfgs.hpp"

#include <vector>

#include "physgrad/error.hpp"

namespace physgrad {

const OptionList<LbfgsOptions>& LbfgsOptions::descriptors() {
  static const OptionList<LbfgsOptions> options = joined<LbfgsOptions>({
      {rule_option("memory", &LbfgsOptions::memory, integer_at_least(1),
                   "curvature pairs m kept"),
       initial_step_option(&LbfgsOptions::initial_step)},
      nested_options(&LbfgsOptions::line_search),
  });
  return options;
}

Lbfgs::Lbfgs(Options options)
    : QuasiNewton(checked("lbfgs", options).initial_step, options.line_search),
      options_(options) {}

Vector Lbfgs::direction(const Vector& gradient) const {
  // First loop, newest pair first: q ← q − aᵢ yᵢ with aᵢ = ρᵢ sᵢᵀq. Then r = H₀ q, and the
  // second loop, oldest first: r ← r + (aᵢ − ρᵢ yᵢᵀr) sᵢ. The result is r = H g.
  std::vector<double> a(pairs_.size());
  Vector q = gradient;
  for (std::size_t i = pairs_.size(); i-- > 0;) {
    a[i] = pairs_[i].rho * pairs_[i].s.dot(q);
    q -= a[i] * pairs_[i].y;
  }
  const double gamma =
      pairs_.empty() ? 1.0 : 1 / (pairs_.back().rho * pairs_.back().y.squaredNorm());
  Vector r = gamma * q;
  for (std::size_t i = 0; i < pairs_.size(); ++i) {
    r += (a[i] - pairs_[i].rho * pairs_[i].y.dot(r)) * pairs_[i].s;
  }
  return -r;
}

void Lbfgs::add_pair(const Vector& s, const Vector& y) {
  pairs_.push_back({s, y, 1 / y.dot(s)});
  if (pairs_.size() > static_cast<std::size_t>(options_.memory)) pairs_.pop_front();
}

}  // namespace physgrad
