#include "physgrad/optim/optimizer.hpp"

#include <cmath>
#include <sstream>

#include "physgrad/error.hpp"

namespace physgrad {

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
