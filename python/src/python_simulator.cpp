#include "python_simulator.hpp"

#include "physgrad/autodiff/finite_difference.hpp"
#include "physgrad/error.hpp"

namespace physgrad::python {

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
// of numbers".
DoubleArray as_array(const py::handle& value, const std::string& lead) {
  DoubleArray array;
  try {
    array = DoubleArray::ensure(value);
  } catch (py::error_already_set&) {
  }
  if (!array) {
    throw Error(lead + " " + std::string(py::str(py::type::handle_of(value).attr("__name__"))) +
                ", expected an array of numbers");
  }
  return array;
}

}  // namespace

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
  if (m_ < 0 && py::hasattr(object_, "output_dim")) m_ = object_.attr("output_dim").cast<Index>();
  if (m_ < 0) {
    m_ = call_python(*errors_, "forward", [&] {
      return to_vector(object_.attr("forward")(to_numpy(x0)), name_, "forward").size();
    });
  }
}

Vector PythonSimulator::call_vector(const char* method, const Vector& a, const Vector* b,
                                    Index size) const {
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
  Matrix y(m_, x.cols());
  for (Index i = 0; i < x.cols(); ++i) y.col(i) = call_vector("forward", x.col(i), nullptr, m_);
  return y;
}

Matrix PythonSimulator::finite_difference(const Vector& x) const {
  return finite_difference_jacobian(
      [this](const Vector& at) { return call_vector("forward", at, nullptr, m_); }, x);
}

Matrix PythonSimulator::vjp_batch(const Matrix& x, const Matrix& context, const Matrix& gy) const {
  check_batch(x, context, "vjp_batch");
  Matrix gx(n_, x.cols());
  for (Index i = 0; i < x.cols(); ++i) {
    const Vector xi = x.col(i), gi = gy.col(i);
    gx.col(i) = has_vjp_ ? call_vector("vjp", xi, &gi, n_) : Vector(jacobian(xi).transpose() * gi);
  }
  return gx;
}

Matrix PythonSimulator::jacobian(const Vector& x, const Vector& context) const {
  if (has_vjp_ && !has_jacobian_) return Simulator::jacobian(x, context);
  if (!has_jacobian_) return finite_difference(x);
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
