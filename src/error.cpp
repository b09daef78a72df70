#include "physgrad/error.hpp"

#include <sstream>

namespace physgrad {

void require(bool ok, const char* who, const char* what, double value) {
  if (ok) return;
  std::ostringstream message;
  message << who << ": " << what << ", got " << value;
  throw Error(message.str());
}

}  // namespace physgrad
