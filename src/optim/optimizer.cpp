#include "physgrad/optim/optimizer.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

Step Optimizer::step(const Objective& objective, const Vector& x, const Domain& domain) {
  const std::string rule = id();
  domain.check_dim(x.size(), rule.c_str());
  if (x.size() != objective.dim()) {
    std::ostringstream msg;
    msg << rule << ": x has " << x.size() << " entries, the objective " << objective.dim();
    throw Error(msg.str());
  }
  // The rule sees the simulator only through a CheckedSimulator (minimize() hands one over).
  const Step step = propose(CheckedObjective(objective).objective(), x, domain);
  // An accepted step moves every variable; a rejected trial or a failure may leave dx empty.
  const bool fits = step.delta.size() == x.size() ||
                    (step.status != Step::Status::kOk && step.delta.size() == 0);
  if (!fits) {
    std::ostringstream msg;
    msg << "optimizer '" << rule << "': step returned " << step.delta.size()
        << " entries, expected " << x.size();
    throw Error(msg.str());
  }
  return step;
}

void require_positive(const char* what, double value) {
  if (!(std::isfinite(value) && value > 0)) {
    std::ostringstream msg;
    msg << what << " must be a finite number > 0, got " << value;
    throw Error(msg.str());
  }
}

void require_in_range(const char* what, double value, double lo, double hi) {
  if (!(std::isfinite(value) && value >= lo && value < hi)) {
    std::ostringstream msg;
    msg << what << " must be in [" << lo << ", " << hi << "), got " << value;
    throw Error(msg.str());
  }
}

}  // namespace physgrad
