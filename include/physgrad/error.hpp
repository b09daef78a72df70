// physgrad::Error — the exception type thrown at API boundaries; its message names the
// offending value. NumericalError — numbers that cannot be worked with (NaN/Inf, no convergence).
#pragma once

#include <stdexcept>
#include <string>

namespace physgrad {

// Bad input: a mismatched dimension, a value out of range, an unknown name. The CLI prints the
// message as one line and exits with 2.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Numerical trouble below an update rule: a non-finite operand, a factorization that did not
// converge. The drivers (minimize(), train_step()) turn it into a run that ends with
// "numerical_failure" and this message, instead of letting it escape.
class NumericalError : public Error {
 public:
  explicit NumericalError(const std::string& message) : Error(message) {}
};

}  // namespace physgrad
