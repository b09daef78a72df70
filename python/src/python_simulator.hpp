// PythonSimulator — a Simulator whose methods are a Python object's (numpy in and out): forward
// required; vjp, jacobian, inverse and time_reversal optional, what is missing derived (J by
// central (f(x+h) − f(x−h))/2h or forward (f(x+h) − f(x))/h differences of forward, Jᵀg from J);
// CallbackErrors carries a Python exception out.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <map>
#include <optional>
#include <utility>
#include <vector>
#include <string>

#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/physics/simulator.hpp"

namespace physgrad::python {

namespace py = pybind11;

// A Python exception raised in a callback while the library ran. The callback keeps it here and
// throws CallbackFailed, which unwinds the library; the binding then raises the original
// exception in Python with `context` ("rule lm, iteration 3") added to its message.
// With `stop_on_interrupt` (a run of the experiment framework, which stops in order and keeps
// its checkpoint), the first KeyboardInterrupt is no failure: it becomes the library's stop
// request (`interrupted` set), and the callback is called again for the result the step needs.
struct CallbackErrors {
  std::optional<py::error_already_set> error;
  std::string method;  // the callback that raised it ("forward", "vjp", ...)
  int iteration = 0;   // the iteration the library was in (updated by the caller)
  bool stop_on_interrupt = false;
  bool interrupted = false;
};
struct CallbackFailed : std::exception {
  const char* what() const noexcept override { return "a Python callback raised an exception"; }
};

// Whether `raised` is the KeyboardInterrupt that `errors` takes as a stop request (see above);
// when it is, the request is made.
bool take_interrupt(CallbackErrors& errors, py::error_already_set& raised);
// Keeps `raised` in `errors` (unless one is kept already) and throws CallbackFailed.
[[noreturn]] void keep_and_fail(CallbackErrors& errors, const char* method,
                                py::error_already_set&& raised);

// Runs `body` holding the GIL; a Python exception it raises is kept in `errors` (named `method`)
// and CallbackFailed thrown in its place. Python's pending signals are looked at after every
// call, so that Ctrl-C (KeyboardInterrupt) ends the run even when the callable is a C function
// (np.exp) that runs no Python code of its own.
template <class Body>
auto call_python(CallbackErrors& errors, const char* method, Body&& body) {
  py::gil_scoped_acquire gil;
  for (;;) {
    try {
      auto result = body();
      if (PyErr_CheckSignals() == 0) return result;
      py::error_already_set raised;
      if (take_interrupt(errors, raised)) return result;
      keep_and_fail(errors, method, std::move(raised));
    } catch (py::error_already_set& e) {
      if (take_interrupt(errors, e)) continue;  // interrupted inside: asked again
      keep_and_fail(errors, method, std::move(e));
    }
  }
}

// Raises in Python the exception kept in `errors` (whose message gains " (in CONTEXT, METHOD)"),
// with the GIL held. Call it from the binding after the library unwound with CallbackFailed.
[[noreturn]] void raise_kept(CallbackErrors& errors, const std::string& context);

// An integer argument (a Python int or a NumPy integer, not a bool) in [lowest, highest]; Error
// "WHAT is 'abc', expected an integer" or "… expected an integer in [1, 2147483647]" otherwise.
long long to_integer(const py::handle& value, const std::string& what, long long lowest,
                     long long highest);

// numpy ↔ Eigen copies for the small vectors of the direct problems.
py::array_t<double> to_numpy(const Vector& v);
py::array_t<double> to_numpy(const Matrix& m);  // row-major copy, shape (rows, cols)
// `value` as a vector (any array-like of real numbers — integers or floats — flattened when
// 1 × n or n × 1); throws Error "WHO: METHOD returned ..." for anything else: None, text,
// booleans, complex numbers, dates, objects.
Vector to_vector(const py::handle& value, const std::string& who, const char* method);
// An argument `name` of shape (B, k) (any array-like of numbers) as the k × B matrix of its rows,
// one sample per column; throws Error "WHO: NAME has shape …, expected (B, k)" otherwise.
Matrix to_columns(const py::handle& value, const std::string& who, const char* name);

class PythonSimulator final : public Simulator {
 public:
  // `n` inputs; `m` outputs, or -1 to ask the object (its output_dim, else the size of one
  // forward at x0). Holds a reference to `errors`, which must outlive it.
  PythonSimulator(py::object simulator, Index n, Index m, const Vector& x0,
                  CallbackErrors& errors);

  // How a missing Jacobian is made: central differences (2n forward passes) or forward
  // differences (n + 1).
  enum class Differences { kCentral, kForward };
  void set_differences(Differences kind) { differences_ = kind; }
  static Differences parse_differences(const std::string& text);

  // With the object's inverse_batch(Y, X0) (and forward_batch(X)), asks for the inverses of the
  // columns of `y` from those of `x0` in one call (and the forward passes at the results in one
  // more); inverse() and forward() then answer those exact arguments from what came back. Does
  // nothing for an object without inverse_batch. Call it holding the GIL.
  void answer_inverses(const Matrix& y, const Matrix& x0);

  // The library's counts of this simulator's work made true to the calls of the Python object:
  // a Jacobian made by differences counts its forward passes (2n or n + 1) where the library
  // counted m, and a VJP made from such a Jacobian the same where the library counted 1.
  SimulatorCounts actual(SimulatorCounts library) const;

  std::string name() const override { return name_; }
  Index input_dim() const override { return n_; }
  Index output_dim() const override { return m_; }

  Matrix forward_batch(const Matrix& x, const Matrix& context) const override;
  Matrix vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const override;
  Matrix jacobian(const Vector& x, const Vector& context = {}) const override;
  // Its own jacobian(), or finite differences when it has no vjp (which then comes from J too).
  bool has_jacobian() const override { return has_jacobian_ || !has_vjp_; }

  bool has_inverse() const override { return has_inverse_; }
  Vector inverse(const Vector& y, const Vector& x0, const Vector& context = {}) const override;
  bool has_time_reversal() const override { return has_time_reversal_; }
  Vector time_reversal(const Vector& y, const Vector& context = {}) const override;

 private:
  Vector call_vector(const char* method, const Vector& a, const Vector* b, Index size) const;
  Matrix call_rows(const char* method, const Matrix& a, const Matrix* b, Index size) const;
  Matrix finite_difference(const Vector& x) const;

  py::object object_;
  CallbackErrors* errors_;
  Differences differences_ = Differences::kCentral;
  mutable long long difference_passes_ = 0;      // forward calls made for differences
  mutable long long difference_jacobians_ = 0;   // jacobian() answered by differences
  mutable long long difference_vjps_ = 0;        // VJP samples answered from such a Jacobian
  std::string name_;
  Index n_ = 0, m_ = 0;
  bool has_vjp_ = false, has_jacobian_ = false, has_inverse_ = false, has_time_reversal_ = false;
  bool has_forward_batch_ = false;
  // Results given ahead by a batched call: (method, its arguments one after the other) → result.
  std::map<std::pair<std::string, std::vector<double>>, Vector> answers_;
};

}  // namespace physgrad::python
