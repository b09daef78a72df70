// physgrad::Error — the exception type thrown at API boundaries; its message names the
// offending value. NumericalError — numbers that cannot be worked with (NaN/Inf, no convergence).
#pragma once

#include <stdexcept>
#include <string>

namespace physgrad {

// Bad input: a mismatched dimension, a value out of range, an unknown name. The CLI prints the
// message as one line and exits with 2.
// what() is a C string: a NUL inside the message (from a value quoted in it) is written as \x00
// so that it cannot cut the message short.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(without_nul(message)) {}

 private:
  static std::string without_nul(const std::string& message) {
    std::string text;
    for (const char c : message) {
      if (c == '\0') {
        text += "\\x00";
      } else {
        text += c;
      }
    }
    return text;
  }
};

// Throws Error "WHO: METHOD returned 0×0, expected 2×4" for a value of the wrong shape that a
// user's model returned (a vector: cols and expected_cols < 0, "returned 3 entries, expected 4").
[[noreturn]] inline void throw_wrong_result(const std::string& who, const char* method,
                                            long long rows, long long cols,
                                            long long expected_rows, long long expected_cols) {
  const auto shape = [](long long r, long long c) {
    return c < 0 ? std::to_string(r) : std::to_string(r) + "×" + std::to_string(c);
  };
  throw Error(who + ": " + method + " returned " + shape(rows, cols) +
              (cols < 0 ? " entries" : "") + ", expected " + shape(expected_rows, expected_cols));
}

// Throws Error "WHO: WHAT, got VALUE" unless `ok`: the check of one argument of WHO, e.g.
// require(xi > 0, "sin_rotation", "xi must be finite and positive", xi).
void require(bool ok, const char* who, const char* what, double value);

// Numerical trouble below an update rule: a non-finite operand, a factorization that did not
// converge. The drivers (minimize(), train_step()) turn it into a run that ends with
// "numerical_failure" and this message, instead of letting it escape.
class NumericalError : public Error {
 public:
  explicit NumericalError(const std::string& message) : Error(message) {}
};

}  // namespace physgrad
