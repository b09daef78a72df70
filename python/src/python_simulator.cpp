#include "python_simulator.hpp"

#include <cmath>
#include <limits>
#include <map>

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"
#include "physgrad/stop.hpp"

namespace physgrad::python {

bool take_interrupt(CallbackErrors& errors, py::error_already_set& raised) {
  if (!errors.stop_on_interrupt || errors.interrupted || !raised.matches(PyExc_KeyboardInterrupt)) {
    return false;
  }
  errors.interrupted = true;
  request_stop();
  return true;
}

void keep_and_fail(CallbackErrors& errors, const char* method, py::error_already_set&& raised) {
  if (!errors.error) {
    errors.error.emplace(std::move(raised));
    errors.method = method;
  }
  throw CallbackFailed();
}

void raise_kept(CallbackErrors& errors, const std::string& context) {
  py::error_already_set error = std::move(*errors.error);
  errors.error.reset();
  const std::string added = " (in " + context + ", " + errors.method + ")";
  py::object value = error.value();
  py::tuple args = value.attr("args");
  if (args.size() >= 1 && py::isinstance<py::str>(args[0])) {
    py::list changed(args);
    changed[0] = py::str(std::string(py::str(args[0])) + added);
    value.attr("args") = py::tuple(changed);
  } else {
    value.attr("add_note")(added.substr(1));
  }
  throw error;
}

py::array_t<double> to_numpy(const Vector& v) {
  py::array_t<double> out(v.size());
  std::copy(v.data(), v.data() + v.size(), out.mutable_data());
  return out;
}

py::array_t<double> to_numpy(const Matrix& m) {
  py::array_t<double> out({m.rows(), m.cols()});
  auto view = out.mutable_unchecked<2>();
  for (Index i = 0; i < m.rows(); ++i) {
    for (Index j = 0; j < m.cols(); ++j) view(i, j) = m(i, j);
  }
  return out;
}

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// `value` as a C-ordered double array; otherwise an Error "<lead> <its type>, expected an array
// of numbers". Only integers and floats convert: None, text, booleans, complex numbers, dates
// and objects, which a forced cast would turn into numbers, are refused.
DoubleArray as_array(const py::handle& value, const std::string& lead) {
  DoubleArray array;  // (an empty array, not a null handle)
  std::string kind;
  bool converted = false;
  try {
    const py::array raw = py::array::ensure(value);
    if (raw) kind = std::string(1, raw.dtype().kind());
    if (kind == "i" || kind == "u" || kind == "f") {
      array = DoubleArray::ensure(raw);
      converted = static_cast<bool>(array);
    }
  } catch (py::error_already_set&) {
  }
  if (!converted) {
    std::string type = py::str(py::type::handle_of(value).attr("__name__"));
    if (!kind.empty() && (type == "list" || type == "tuple" || type == "ndarray")) {
      static const std::map<std::string, std::string> kinds = {
          {"b", "booleans"}, {"c", "complex numbers"}, {"M", "dates"}, {"m", "time spans"},
          {"O", "objects"},  {"U", "text"},            {"S", "bytes"}, {"V", "records"}};
      const auto found = kinds.find(kind);
      type += " of " + (found == kinds.end() ? "dtype kind " + kind : found->second);
    }
    throw Error(lead + " " + type + ", expected an array of numbers");
  }
  return array;
}

}  // namespace

long long to_integer(const py::handle& value, const std::string& what, long long lowest,
                     long long highest) {
  const std::string shown = py::str(py::repr(value));
  if (py::isinstance<py::bool_>(value) || !PyIndex_Check(value.ptr())) {
    throw Error(what + " is " + shown + ", expected an integer");
  }
  const py::int_ integer = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  int overflow = 0;
  const long long result = PyLong_AsLongLongAndOverflow(integer.ptr(), &overflow);
  if (overflow != 0 || result < lowest || result > highest) {
    throw Error(what + " is " + shown + ", expected an integer in [" + std::to_string(lowest) +
                ", " + std::to_string(highest) + "]");
  }
  return result;
}

Vector to_vector(const py::handle& value, const std::string& who, const char* method) {
  const DoubleArray array = as_array(value, who + ": " + method + " returned");
  if (array.ndim() > 2 || (array.ndim() == 2 && array.shape(0) != 1 && array.shape(1) != 1)) {
    throw_wrong_result(who, method, array.ndim() >= 1 ? array.shape(0) : 1,
                       array.ndim() >= 2 ? array.shape(1) : -1, array.size(), -1);
  }
  return Eigen::Map<const Vector>(array.data(), array.size());
}

Matrix to_columns(const py::handle& value, const std::string& who, const char* name) {
  const DoubleArray array = as_array(value, who + ": " + name + " is a");
  if (array.ndim() != 2) {
    std::string shape;
    for (py::ssize_t d = 0; d < array.ndim(); ++d) {
      shape += (d == 0 ? "" : ", ") + std::to_string(array.shape(d));
    }
    throw Error(who + ": " + name + " has shape (" + shape +
                "), expected (B, k): one sample a row");
  }
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  return Eigen::Map<const RowMajor>(array.data(), array.shape(0), array.shape(1)).transpose();
}

PythonSimulator::PythonSimulator(py::object simulator, Index n, Index m, const Vector& x0,
                                 CallbackErrors& errors)
    : object_(std::move(simulator)), errors_(&errors), n_(n), m_(m) {
  if (!py::hasattr(object_, "forward")) {
    throw Error("simulator: the object has no forward(x) method");
  }
  name_ = py::hasattr(object_, "name") ? std::string(py::str(object_.attr("name")))
                                       : std::string(py::str(py::type::handle_of(object_).attr(
                                             "__name__")));
  has_vjp_ = py::hasattr(object_, "vjp");
  has_jacobian_ = py::hasattr(object_, "jacobian");
  has_inverse_ = py::hasattr(object_, "inverse");
  has_time_reversal_ = py::hasattr(object_, "time_reversal");
  has_forward_batch_ = py::hasattr(object_, "forward_batch");
  if (m_ < 0 && py::hasattr(object_, "output_dim")) {
    m_ = to_integer(object_.attr("output_dim"), "simulator '" + name_ + "': output_dim", 1,
                    std::numeric_limits<int>::max());
  }
  if (m_ < 0) {
    m_ = call_python(*errors_, "forward", [&] {
      return to_vector(object_.attr("forward")(to_numpy(x0)), name_, "forward").size();
    });
  }
}

namespace {

std::pair<std::string, std::vector<double>> answer_key(const char* method, const Vector& a,
                                                       const Vector* b) {
  std::vector<double> arguments(a.data(), a.data() + a.size());
  if (b != nullptr) arguments.insert(arguments.end(), b->data(), b->data() + b->size());
  return {method, std::move(arguments)};
}

}  // namespace

Matrix PythonSimulator::call_rows(const char* method, const Matrix& a, const Matrix* b,
                                  Index size) const {
  const std::string who = "simulator '" + name_ + "'";
  const std::string batch_method = std::string(method) + "_batch";
  return call_python(*errors_, batch_method.c_str(), [&] {
    const Matrix a_rows = a.transpose(), b_rows = b == nullptr ? Matrix() : Matrix(b->transpose());
    const py::object out = b == nullptr ? object_.attr(batch_method.c_str())(to_numpy(a_rows))
                                        : object_.attr(batch_method.c_str())(to_numpy(a_rows),
                                                                             to_numpy(b_rows));
    const Matrix columns = to_columns(out, who, (batch_method + " result").c_str());
    if (columns.rows() != size || columns.cols() != a.cols()) {
      throw_wrong_result(who, batch_method.c_str(), columns.cols(), columns.rows(), a.cols(), size);
    }
    return columns;
  });
}

void PythonSimulator::answer_inverses(const Matrix& y, const Matrix& x0) {
  if (!py::hasattr(object_, "inverse_batch")) return;
  const Matrix x = call_rows("inverse", y, &x0, n_);
  for (Index i = 0; i < y.cols(); ++i) {
    const Vector yi = y.col(i), x0i = x0.col(i);
    answers_[answer_key("inverse", yi, &x0i)] = x.col(i);
  }
  if (!has_forward_batch_ || !all_finite(x)) return;
  const Matrix y_at = call_rows("forward", x, nullptr, m_);
  for (Index i = 0; i < x.cols(); ++i) {
    answers_[answer_key("forward", x.col(i), nullptr)] = y_at.col(i);
  }
}

Vector PythonSimulator::call_vector(const char* method, const Vector& a, const Vector* b,
                                    Index size) const {
  if (!answers_.empty()) {
    const auto found = answers_.find(answer_key(method, a, b));
    if (found != answers_.end()) return found->second;
  }
  Vector result = call_python(*errors_, method, [&] {
    py::object out = b == nullptr ? object_.attr(method)(to_numpy(a))
                                  : object_.attr(method)(to_numpy(a), to_numpy(*b));
    return to_vector(out, "simulator '" + name_ + "'", method);
  });
  if (result.size() != size) {
    throw_wrong_result("simulator '" + name_ + "'", method, result.size(), -1, size, -1);
  }
  return result;
}

Matrix PythonSimulator::forward_batch(const Matrix& x, const Matrix& context) const {
  check_batch(x, context, "forward_batch");
  if (has_forward_batch_ && x.cols() > 1) return call_rows("forward", x, nullptr, m_);
  Matrix y(m_, x.cols());
  for (Index i = 0; i < x.cols(); ++i) y.col(i) = call_vector("forward", x.col(i), nullptr, m_);
  return y;
}

PythonSimulator::Differences PythonSimulator::parse_differences(const std::string& text) {
  if (text == "central") return Differences::kCentral;
  if (text == "forward") return Differences::kForward;
  throw Error("minimize: differences '" + text + "' is not 'central' or 'forward'");
}

SimulatorCounts PythonSimulator::actual(SimulatorCounts library) const {
  library.passes += difference_passes_ - m_ * difference_jacobians_ - difference_vjps_;
  library.forward += difference_passes_;
  return library;
}

Matrix PythonSimulator::finite_difference(const Vector& x) const {
  const auto f = [this](const Vector& at) {
    ++difference_passes_;
    return call_vector("forward", at, nullptr, m_);
  };
  if (differences_ == Differences::kCentral) return finite_difference_jacobian(f, x);
  // (f(x + hᵢeᵢ) − f(x))/hᵢ with hᵢ = √ε·max(1, |xᵢ|): error O(h), n + 1 passes.
  const double h = std::sqrt(std::numeric_limits<double>::epsilon());
  const Vector y = f(x);
  Matrix jacobian(m_, x.size());
  for (Index i = 0; i < x.size(); ++i) {
    Vector shifted = x;
    shifted(i) += h * std::max(1.0, std::abs(x(i)));
    const double step = shifted(i) - x(i);  // the step as represented
    jacobian.col(i) = (f(shifted) - y) / step;
  }
  return jacobian;
}

Matrix PythonSimulator::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_batch(x, context, "vjp_batch");
  Matrix gx(n_, x.cols());
  for (Index i = 0; i < x.cols(); ++i) {
    const Vector xi = x.col(i), gi = gy.col(i);
    if (has_vjp_) {
      gx.col(i) = call_vector("vjp", xi, &gi, n_);
    } else if (has_jacobian_) {
      gx.col(i) = jacobian(xi).transpose() * gi;
    } else {
      ++difference_vjps_;
      gx.col(i) = finite_difference(xi).transpose() * gi;
    }
  }
  return gx;
}

Matrix PythonSimulator::jacobian(const Vector& x, const Vector& context) const {
  if (has_vjp_ && !has_jacobian_) return Simulator::jacobian(x, context);
  if (!has_jacobian_) {
    ++difference_jacobians_;
    return finite_difference(x);
  }
  return call_python(*errors_, "jacobian", [&] {
    const py::object out = object_.attr("jacobian")(to_numpy(x));
    const DoubleArray array = as_array(out, "simulator '" + name_ + "': jacobian returned");
    if (array.ndim() != 2 || array.shape(0) != m_ || array.shape(1) != n_) {
      throw_wrong_result("simulator '" + name_ + "'", "jacobian",
                         array.ndim() >= 1 ? array.shape(0) : 0,
                         array.ndim() >= 2 ? array.shape(1) : 0, m_, n_);
    }
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    return Matrix(Eigen::Map<const RowMajor>(array.data(), m_, n_));
  });
}

Vector PythonSimulator::inverse(const Vector& y, const Vector& x0, const Vector& context) const {
  if (!has_inverse_) return Simulator::inverse(y, x0, context);
  return call_vector("inverse", y, &x0, n_);
}

Vector PythonSimulator::time_reversal(const Vector& y, const Vector& context) const {
  if (!has_time_reversal_) return Simulator::time_reversal(y, context);
  return call_vector("time_reversal", y, nullptr, n_);
}

}  // namespace physgrad::python
