// SIP from PyTorch: the proxy targets x̃ᵢ = P⁻¹(yᵢ + η(y*ᵢ − yᵢ); xᵢ) of a batch by the library's
// local inverse on a Python simulator, as SipUpdate::step makes them (learn/sip.cpp); an analytic
// inverse of a simulator with inverse_batch (and forward_batch) is asked once for the batch.
#include <pybind11/numpy.h>

#include <chrono>

#include "bindings.hpp"
#include "physgrad/error.hpp"
#include "physgrad/inversion/y_step.hpp"
#include "physgrad/learn/sip.hpp"
#include "physgrad/text.hpp"
#include "python_simulator.hpp"

namespace physgrad::python {

namespace {

// sip's options: the catalogue's defaults with the keyword settings, checked as SipUpdate checks
// them. A name sip does not take is an Error (with_settings alone passes over an option of
// another learning rule, such as hig's rcond).
SipOptions sip_options(const py::dict& given) {
  const RuleSettings settings = rule_settings(given);
  check_rule_option_names(RuleKind::kLearning, "sip", settings);
  return checked("sip", std::get<SipOptions>(with_settings(find_rule(RuleKind::kLearning, "sip"),
                                                           settings)));
}

// sip's params() for those options: every option that applies, by name.
py::object sip_params(const py::dict& settings) {
  return to_python(SipUpdate(sip_options(settings)).params());
}

// x (B, n), y and y* (B, m) as given, one sample a row (held one a column), with B ≥ 1.
void check_sip_shapes(const Matrix& x, const Matrix& y, const Matrix& target) {
  const Index count = x.cols();
  if (y.cols() == count && target.rows() == y.rows() && target.cols() == count && count > 0) {
    return;
  }
  const auto shape = [](const Matrix& m) {  // as given: one sample a row
    return "(" + std::to_string(m.cols()) + ", " + std::to_string(m.rows()) + ")";
  };
  throw Error("sip: x has shape " + shape(x) + ", y " + shape(y) + " and the target y* " +
              shape(target) + ", expected (B, n), (B, m) and (B, m) with B ≥ 1");
}

// "sip: sample I of B: ", the start of a message about one sample.
std::string sip_sample(Index i, Index count) {
  return "sip: sample " + std::to_string(i) + " of " + std::to_string(count) + ": ";
}

// y + Δy for each sample (one a column), Δy = y_step(L2, y, y*, η); a non-finite x, y or y* is
// a NumericalError naming the sample.
Matrix sip_y_targets(const Matrix& x, const Matrix& y, const Matrix& target,
                     const SipOptions& options) {
  const L2Loss loss;
  const Index count = x.cols();
  Matrix y_targets(y.rows(), count);
  Index i = 0;
  try {
    for (; i < count; ++i) {
      if (!all_finite(x.col(i))) throw NumericalError("the network output x is not finite");
      if (!all_finite(y.col(i))) throw NumericalError("the simulator output y is not finite");
      if (!all_finite(target.col(i))) throw NumericalError("the target y* is not finite");
      const Vector yi = y.col(i);
      y_targets.col(i) = yi + y_step(loss, yi, target.col(i), options.y_step);
    }
  } catch (const NumericalError& e) {
    throw NumericalError(sip_sample(i, count) + e.what());
  }
  return y_targets;
}

// An analytic inverse (or, with the method auto, one the simulator has) is asked once for the
// whole batch, when the object has inverse_batch; local_inverse() then reads its answers.
void answer_sip_inverses(PythonSimulator& simulator, const Matrix& y_targets, const Matrix& x,
                         const SipOptions& options, CallbackErrors& errors) {
  const InverseMethod how = options.inverse.method;
  const bool analytic =
      how == InverseMethod::kAnalytic || (how == InverseMethod::kAuto && simulator.has_inverse());
  if (!analytic) return;
  const std::string batch = "the batch of " + std::to_string(x.cols());
  try {
    simulator.answer_inverses(y_targets, x);  // one batched call, when the object has one
  } catch (const CallbackFailed&) {
    raise_kept(errors, "sip, " + batch + ", local inverse " + to_string(how));
  } catch (const Error& e) {
    throw Error("sip: " + batch + ": " + e.what());
  }
}

// Each sample's x̃ = P⁻¹(y + Δy; x) by local_inverse(), with what it took.
struct SipInverses {
  explicit SipInverses(Index rows, Index count)
      : x_tilde(rows, count), residual(count), converged(count) {}
  Matrix x_tilde;
  Vector residual;
  py::array_t<bool> converged;
  SimulatorCounts counts;
  long long iterations = 0, evaluations = 0;
};

SipInverses sip_local_inverses(PythonSimulator& simulator, const Matrix& y_targets,
                               const Matrix& x, const SipOptions& options, CallbackErrors& errors) {
  const std::string method = to_string(options.inverse.method);
  const Index count = x.cols();
  SipInverses out(x.rows(), count);
  Index i = 0;
  try {
    py::gil_scoped_release released;
    for (; i < count; ++i) {
      const LocalInverseResult result =
          local_inverse(simulator, y_targets.col(i), x.col(i), Vector(), options.inverse);
      if (!all_finite(result.x)) {
        throw NumericalError("the local inverse (" + method + ") gave no finite preimage");
      }
      out.x_tilde.col(i) = result.x;
      out.residual(i) = result.residual;
      out.converged.mutable_at(i) = result.converged;
      out.iterations += result.iterations;
      out.evaluations += result.evaluations;
      out.counts += result.counts;
    }
  } catch (const CallbackFailed&) {
    raise_kept(errors, "sip, sample " + std::to_string(i) + ", local inverse " + method);
  } catch (const NumericalError& e) {
    throw NumericalError(sip_sample(i, count) + e.what());
  } catch (const Error& e) {
    throw Error(sip_sample(i, count) + e.what());
  }
  return out;
}

// SIP's proxy targets for one batch, made as SipUpdate::step makes them (learn/sip.cpp): for each
// sample x̃ᵢ = P⁻¹(yᵢ + Δyᵢ; xᵢ) by local_inverse with sip's inverse options, where
// Δyᵢ = y_step(L2, yᵢ, y*ᵢ, η) = η(y*ᵢ − yᵢ). x (B, n), y and y* (B, m) hold one sample a row.
// Where SipUpdate hands a failed sample on as a NaN step, this raises, naming the sample: a
// non-finite x, y, y* or x̃ (NumericalError), a result of the wrong size (Error), an exception
// of the simulator's (its own type).
py::dict sip_targets(const py::object& sim, const py::object& x_value, const py::object& y_value,
                     const py::object& target_value, const py::dict& settings) {
  const SipOptions options = sip_options(settings);
  const Matrix x = to_columns(x_value, "sip", "x");
  const Matrix y = to_columns(y_value, "sip", "y");
  const Matrix target = to_columns(target_value, "sip", "the target y*");
  check_sip_shapes(x, y, target);
  CallbackErrors errors;
  PythonSimulator simulator(sim, x.rows(), y.rows(), x.col(0), errors);
  const auto start = std::chrono::steady_clock::now();
  const Matrix y_targets = sip_y_targets(x, y, target, options);
  answer_sip_inverses(simulator, y_targets, x, options, errors);
  const SipInverses inverses = sip_local_inverses(simulator, y_targets, x, options, errors);
  py::dict out;
  out["x"] = to_numpy(Matrix(inverses.x_tilde.transpose()));
  out["residual"] = to_numpy(inverses.residual);
  out["converged"] = inverses.converged;
  out["iterations"] = inverses.iterations;
  out["evaluations"] = inverses.evaluations;
  out["counts"] = counts_dict(simulator.actual(inverses.counts));
  out["inversion_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace

void bind_sip(py::module_& m) {
  m.def("_sip_params", &sip_params, py::arg("settings"));
  m.def("_sip_targets", &sip_targets, py::arg("simulator"), py::arg("x"), py::arg("y"),
        py::arg("target"), py::arg("settings"));
}

}  // namespace physgrad::python
