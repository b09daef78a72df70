#include "physgrad/optim/optimizer.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

Step Optimizer::step(const Objective& objective, const Vector& x, const Domain& domain) {
  domain.check_dim(x.size(), id().c_str());
  return propose(objective, x, domain);
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
