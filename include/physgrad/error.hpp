// physgrad::Error — the one exception type thrown at API boundaries.
// Its message names the offending value; the CLI prints it as one line and exits with 2.
#pragma once

#include <stdexcept>
#include <string>

namespace physgrad {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace physgrad
