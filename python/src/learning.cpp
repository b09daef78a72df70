// Learning from PyTorch: the Jacobian step of HIG and Gauss-Newton (HigUpdate) on a per-sample
// Jacobian given as an array that is read in place, and a reference case's first step computed
// by the library alone, for comparison. (SIP's targets: sip.cpp.)
#include <pybind11/numpy.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>

#include "bindings.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/learn/hig.hpp"
#include "physgrad/learn/mapped_jacobian.hpp"
#include "registry.hpp"
#include "physgrad/text.hpp"
#include "physgrad/threads.hpp"
#include "physgrad/train/step.hpp"
#include "python_simulator.hpp"

namespace physgrad::python {

namespace {

// A Jacobian of shape (B, m, P) or (B·m, P), C-contiguous: float64 read where it lies, float32
// converted once into a double copy (column-major P × B·m, the transpose of the given layout:
// the same entries in the same order).
struct JacobianArray {
  Index batch = 0, outputs = 1, cols = 0;
  const double* given = nullptr;  // float64 only
  Matrix converted;               // float32 only
  const double* data() const { return given != nullptr ? given : converted.data(); }
};

JacobianArray read_jacobian_array(const py::array& jacobian) {
  if (jacobian.ndim() != 2 && jacobian.ndim() != 3) {
    throw Error("jacobian_step: the Jacobian has " + std::to_string(jacobian.ndim()) +
                " dimensions, expected (B, m, P) or (B·m, P)");
  }
  if (!(jacobian.flags() & py::array::c_style)) {
    throw Error("jacobian_step: the Jacobian is not C-contiguous (make it contiguous first)");
  }
  JacobianArray j;
  j.batch = jacobian.shape(0);
  j.outputs = jacobian.ndim() == 3 ? jacobian.shape(1) : 1;
  j.cols = jacobian.shape(jacobian.ndim() - 1);
  if (py::isinstance<py::array_t<double>>(jacobian)) {
    j.given = static_cast<const double*>(jacobian.data());
  } else if (py::isinstance<py::array_t<float>>(jacobian)) {
    using RowMajorFloat = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    j.converted = Eigen::Map<const RowMajorFloat>(static_cast<const float*>(jacobian.data()),
                                                  j.batch * j.outputs, j.cols)
                      .transpose()
                      .cast<double>();
  } else {
    throw Error("jacobian_step: the Jacobian's dtype is " +
                std::string(py::str(jacobian.dtype())) + ", expected float64 or float32");
  }
  return j;
}

// A NaN or Inf in J would only show as an overflow deep in the eigensolve: named here.
void check_jacobian_finite(const JacobianArray& j) {
  const Eigen::Map<const Vector> entries(j.data(), j.batch * j.outputs * j.cols);
  if (all_finite(entries)) return;
  Index first = 0;
  while (std::isfinite(entries(first))) ++first;
  // The entries in the given row-major order (B·m × P), also in the converted copy.
  const Index row = first / j.cols;
  const Index column = first % j.cols;
  throw NumericalError("jacobian_step: the Jacobian has " +
                       std::to_string((!entries.array().isFinite()).count()) +
                       " non-finite entries, the first " + report_number(entries(first)) +
                       " at sample " + std::to_string(row / j.outputs) + ", output " +
                       std::to_string(row % j.outputs) + ", parameter " + std::to_string(column));
}

// ∂L/∂y, finite, one entry per row of J.
Vector read_loss_gradient_y(const py::object& loss_gradient_y, Index rows) {
  const Vector g = to_vector(loss_gradient_y, "jacobian_step", "loss_gradient_y");
  if (!all_finite(g)) {
    throw NumericalError("jacobian_step: dL/dy has a non-finite entry");
  }
  if (g.size() != rows) {
    throw Error("jacobian_step: dL/dy has " + std::to_string(g.size()) + " entries, the Jacobian " +
                std::to_string(rows) + " rows");
  }
  return g;
}

// What the step did: the path and spectrum of the inversion, the rule's state for the next
// step, where J was read and the times.
py::dict jacobian_step_info(const HigUpdate& update, const MappedJacobian& mapped,
                            const JacobianArray& j, const Step& step) {
  py::dict info;
  const PowerPinvInfo& last = update.last_info();
  info["backend"] = to_string(last.backend);
  info["rank"] = last.rank;
  info["sigma_max"] = last.sigma_max;
  info["sigma_min_kept"] = last.sigma_min_kept;
  info["rcond_used"] = last.rcond_used;
  info["precision"] = to_string(last.precision);
  info["eigensolver"] = to_string(last.eigensolver);
  info["float_rejected"] = last.float_rejected;
  info["state"] = to_python(update.state());
  info["data_address"] = reinterpret_cast<std::uintptr_t>(mapped.data());
  info["converted"] = j.converted.size() != 0;
  info["jacobian_seconds"] = step.jacobian_seconds;
  info["inversion_seconds"] = step.inversion_seconds;
  return info;
}

// Δθ = −η J^{−κ} g for J given as an array of shape (B, m, P) or (B·m, P), C-contiguous: float64
// is read where it lies; float32 is converted once into a double copy (the step is double).
py::tuple jacobian_step(const py::array& jacobian, const py::object& loss_gradient_y, double lr,
                        double kappa, double rcond, const std::string& backend,
                        const std::string& precision, const std::string& eigensolver,
                        const py::object& previous) {
  const JacobianArray j = read_jacobian_array(jacobian);
  check_jacobian_finite(j);
  const Vector g = read_loss_gradient_y(loss_gradient_y, j.batch * j.outputs);
  HigUpdate update({.lr = lr,
                    .cut = {.kappa = kappa, .rcond = rcond},
                    .backend = parse_pinv_backend(backend),
                    .precision = parse_pinv_precision(precision),
                    .eigensolver = parse_pinv_eigensolver(eigensolver)});
  if (!previous.is_none()) {
    // The previous step's info["state"]: its spectrum guides the auto choices of this one.
    const std::string text = py::str(py::module_::import("json").attr("dumps")(previous));
    update.restore(nlohmann::json::parse(text), j.cols);
  }
  const auto mapped = std::make_shared<MappedJacobian>(j.data(), j.batch, j.outputs, j.cols);
  BatchState state;
  state.batch_size = j.batch;
  state.jacobian = mapped;
  state.loss_gradient_y = g;
  Step step;
  {
    py::gil_scoped_release released;
    step = update.step(state);
  }
  // A step that is not finite would write ±inf or NaN into the parameters: refused.
  if (!all_finite(step.delta)) {
    throw NumericalError("jacobian_step: the step Δθ = −lr·J^−κ·dL/dy (lr " + report_number(lr) +
                         ", κ " + report_number(kappa) + ") is not finite in " +
                         std::to_string((!step.delta.array().isFinite()).count()) + " of " +
                         std::to_string(step.delta.size()) +
                         " entries (lr too large for this J?); nothing was changed");
  }
  return py::make_tuple(to_numpy(step.delta), jacobian_step_info(update, *mapped, j, step));
}

// Seconds per step of `repeats` steps made in one C++ loop on the same mapped J (no Python
// between them): what jacobian_step costs without its binding, for bench/python_step.py.
double time_jacobian_step(const py::array_t<double, py::array::c_style>& jacobian,
                          const py::object& loss_gradient_y, double lr, double kappa,
                          double rcond, int repeats, const std::string& precision,
                          const std::string& eigensolver) {
  if (jacobian.ndim() != 3 || repeats < 1) {
    throw Error("time_jacobian_step: expected J of shape (B, m, P) and repeats ≥ 1");
  }
  HigUpdate update({.lr = lr,
                    .cut = {.kappa = kappa, .rcond = rcond},
                    .precision = parse_pinv_precision(precision),
                    .eigensolver = parse_pinv_eigensolver(eigensolver)});
  BatchState state;
  state.jacobian = std::make_shared<MappedJacobian>(jacobian.data(), jacobian.shape(0),
                                                    jacobian.shape(1), jacobian.shape(2));
  state.loss_gradient_y = to_vector(loss_gradient_y, "time_jacobian_step", "loss_gradient_y");
  py::gil_scoped_release released;
  const auto start = std::chrono::steady_clock::now();
  for (int r = 0; r < repeats; ++r) update.step(state);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / repeats;
}

// hig's or gn's options (`rule`), checked as HigUpdate checks them: what HIG(...) and GN(...)
// check when they are made and when a param group is added; their params() by name.
py::object hig_params(const std::string& rule, const py::dict& given) {
  const RuleSettings settings = rule_settings(given);
  check_rule_option_names(RuleKind::kLearning, rule, settings);
  const auto options =
      checked(rule, std::get<HigOptions>(with_settings(find_rule(RuleKind::kLearning, rule),
                                                       settings)));
  return to_python(HigUpdate(options).params());
}

// A reference case's first batch (run/cases/registry.hpp): the stacked Jacobian as
// (B, m, P) and ∂(mean L)/∂y as (B, m), both sample-major, θ, and the first step of rule `rule`
// with the case's options computed by the library twice: "delta" from the network's own stacked
// Jacobian (J Jᵀ from the layer factors, as train() steps), "delta_formed" from the formed J
// returned here (J Jᵀ by dsyrk on it, as a step on a given Jacobian computes it).
py::dict reference_step(const std::string& name, Index batch, const std::string& rule) {
  const run::ReferenceCase c = experiments::builtin_registry().reference(name, batch);
  const std::unique_ptr<LearningUpdate> update = c.update(rule);
  if (update->need() != UpdateNeed::kStackedJacobian) {
    throw Error("reference_step: rule '" + rule + "' does not step on the stacked Jacobian");
  }
  auto cache = c.network.new_cache();
  const BatchState state = evaluate_batch(c.network, c.problem(), c.batch,
                                          UpdateNeed::kStackedJacobian, *cache);
  const Vector delta = update->step(state).delta;
  const Matrix j = state.jacobian->materialize();  // row k·B + i
  const Index b = state.jacobian->batch(), m = state.jacobian->outputs(), p = j.cols();
  py::array_t<double> jacobian({b, m, p});
  py::array_t<double> gy({b, m});
  auto jv = jacobian.mutable_unchecked<3>();
  auto gv = gy.mutable_unchecked<2>();
  for (Index i = 0; i < b; ++i) {
    for (Index k = 0; k < m; ++k) {
      gv(i, k) = state.loss_gradient_y(k * b + i);
      for (Index q = 0; q < p; ++q) jv(i, k, q) = j(k * b + i, q);
    }
  }
  BatchState formed;
  formed.batch_size = b;
  formed.jacobian = std::make_shared<MappedJacobian>(jacobian.data(), b, m, p);
  formed.loss_gradient_y = Eigen::Map<const Vector>(gy.data(), b * m);
  const Vector delta_formed = c.update(rule)->step(formed).delta;
  py::dict out;
  out["delta_formed"] = to_numpy(delta_formed);
  out["jacobian"] = jacobian;
  out["loss_gradient_y"] = gy;
  out["delta"] = to_numpy(delta);
  out["parameters"] = to_numpy(Vector(c.network.parameters()));
  out["loss"] = state.loss;
  out["params"] = to_python(update->params());
  return out;
}

}  // namespace

void bind_learning(py::module_& m) {
  // hig's defaults in the catalogue (HigUpdate::rules()), not written again here.
  const auto hig = std::get<HigOptions>(find_rule(RuleKind::kLearning, "hig").defaults);
  m.def("jacobian_step", &jacobian_step, py::arg("jacobian"), py::arg("loss_gradient_y"),
        py::arg("lr") = hig.lr, py::arg("kappa") = hig.cut.kappa,
        py::arg("rcond") = hig.cut.rcond,
        py::arg("backend") = to_string(hig.backend), py::arg("precision") = to_string(hig.precision),
        py::arg("eigensolver") = to_string(hig.eigensolver), py::arg("previous") = py::none(),
        "Δθ = −lr·J^{−κ}·dL/dy (HigUpdate) for J of shape (B, m, P) or (B·m, P), C-contiguous "
        "float64 (read in place) or float32 (converted once); returns (Δθ, info). "
        "precision 'double' | 'float' | 'auto' and eigensolver 'full' | 'subset' | 'auto' choose "
        "the eigensolve (auto follows `previous`, the info['state'] of the previous step).");
  m.def("_time_jacobian_step", &time_jacobian_step, py::arg("jacobian"),
        py::arg("loss_gradient_y"), py::arg("lr"), py::arg("kappa"), py::arg("rcond"),
        py::arg("repeats"), py::arg("precision") = "double", py::arg("eigensolver") = "auto");
  m.def("_hig_params", &hig_params, py::arg("rule"), py::arg("settings"));
  m.def("blas_core", &blas_core,
        "The kernel set OpenBLAS chose for this CPU ('' for another BLAS).");
  m.def("blas_core_note", &blas_core_note,
        "A one-line note when OpenBLAS runs generic kernels on a CPU with AVX2, else ''.");
  m.def("reference_step", &reference_step, py::arg("name") = "oscillators",
        py::arg("batch") = 128, py::arg("rule") = "hig",
        "A reference case's first batch and the library's first step of `rule` on it.");
}

}  // namespace physgrad::python
