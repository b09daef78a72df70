// Direct optimization from Python: minimize() of a Python simulator with any direct rule, the
// local inverse, and the rule catalogue.
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "physgrad/catalogue.hpp"
#include "physgrad/error.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/text.hpp"
#include "python_simulator.hpp"

namespace physgrad::python {

RuleSettings rule_settings(const py::dict& given) {
  RuleSettings settings;
  for (const auto& [key, value] : given) {
    const std::string name = py::str(key);
    const auto refuse = [&] {
      return Error("rule option " + name + ": " + std::string(py::str(py::repr(value))) +
                   " is not a number or a name");
    };
    if (py::isinstance<py::bool_>(value)) throw refuse();
    if (py::isinstance<py::str>(value)) {
      settings[name] = value.cast<std::string>();
    } else if (py::isinstance<py::int_>(value)) {
      settings[name] = value.cast<long long>();
    } else {
      try {
        settings[name] = value.cast<double>();  // a float, or a NumPy number
      } catch (const py::cast_error&) {
        throw refuse();
      }
    }
  }
  return settings;
}

py::dict counts_dict(const SimulatorCounts& c) {
  static const std::pair<const char*, long long SimulatorCounts::*> kinds[] = {
      {"passes", &SimulatorCounts::passes},       {"forward", &SimulatorCounts::forward},
      {"vjp", &SimulatorCounts::vjp},             {"jacobians", &SimulatorCounts::jacobians},
      {"hessians", &SimulatorCounts::hessians},   {"reversals", &SimulatorCounts::reversals},
      {"inverses", &SimulatorCounts::inverses}};
  py::dict d;
  for (const auto& [name, member] : kinds) d[name] = c.*member;
  return d;
}

namespace {

Vector optional_vector(const py::object& value, const char* name) {
  return value.is_none() ? Vector() : to_vector(value, "minimize", name);
}

// The Python simulator, the loss and the target of one minimize() call.
struct Problem {
  std::optional<PythonSimulator> simulator;
  L2Loss loss;
  Vector target;

  Problem(const py::object& sim, const Vector& x0, const py::object& target_value, double weight,
          CallbackErrors& errors)
      : loss(weight) {
    const Index m =
        target_value.is_none() ? -1 : to_vector(target_value, "minimize", "target").size();
    simulator.emplace(sim, x0.size(), m, x0, errors);
    target = target_value.is_none() ? Vector::Zero(simulator->output_dim())
                                    : to_vector(target_value, "minimize", "target");
  }
};

MinimizeSummary run_minimize(const py::object& sim, const py::object& x0_value,
                             const std::string& rule, const py::object& target, double loss_weight,
                             const py::object& lower, const py::object& upper,
                             const py::object& x_scale, int max_iterations,
                             double loss_tolerance, double relative_loss_tolerance,
                             double gradient_tolerance, double function_tolerance,
                             double parameter_tolerance, long long max_evaluations,
                             double max_seconds, const py::object& callback,
                             const py::dict& options) {
  const Vector x0 = to_vector(x0_value, "minimize", "x0");
  const std::unique_ptr<Optimizer> optimizer = make_optimizer(rule, rule_settings(options));
  MinimizeOptions settings{.max_iterations = max_iterations, .loss_tolerance = loss_tolerance};
  settings.relative_loss_tolerance = relative_loss_tolerance;
  settings.gradient_tolerance = gradient_tolerance;
  settings.function_tolerance = function_tolerance;
  settings.parameter_tolerance = parameter_tolerance;
  settings.lower = optional_vector(lower, "lower");
  settings.upper = optional_vector(upper, "upper");
  settings.x_scale = optional_vector(x_scale, "x_scale");
  settings.max_evaluations = max_evaluations;
  settings.max_seconds = max_seconds;

  std::optional<Problem> problem;
  CallbackErrors errors;  // the iteration is that of the last record, + 1 once it is handled
  settings.callback = [&](const IterationRecord& record) {
    errors.iteration = record.iteration;
    const bool stop = !callback.is_none() && call_python(errors, "callback", [&] {
      return py::cast<bool>(callback(record.iteration, record.loss, to_numpy(record.x)));
    });
    errors.iteration = record.iteration + 1;
    return stop;
  };
  try {
    problem.emplace(sim, x0, target, loss_weight, errors);
    const Objective objective(*problem->simulator, problem->loss, problem->target);
    py::gil_scoped_release released;
    return minimize(*optimizer, objective, x0, settings);
  } catch (const CallbackFailed&) {
    raise_kept(errors, "rule " + rule + ", iteration " + std::to_string(errors.iteration));
  }
}

py::dict run_local_inverse(const py::object& sim, const py::object& y_value,
                           const py::object& x0_value, const std::string& method,
                           double tolerance, int max_iterations, double relative_tolerance,
                           double function_tolerance, double rcond, const py::object& lower,
                           const py::object& upper) {
  const Vector x0 = to_vector(x0_value, "local_inverse", "x0");
  const Vector y = to_vector(y_value, "local_inverse", "y");
  CallbackErrors errors;
  const PythonSimulator simulator(sim, x0.size(), y.size(), x0, errors);
  LocalInverseOptions options;
  options.method = parse_inverse_method(method);
  options.tolerance = tolerance;
  options.max_iterations = max_iterations;
  options.relative_tolerance = relative_tolerance;
  options.function_tolerance = function_tolerance;
  options.rcond = rcond;
  const Vector lo = optional_vector(lower, "lower"), hi = optional_vector(upper, "upper");
  const Domain domain(x0.size(), lo, hi, Vector());
  LocalInverseResult result;
  try {
    py::gil_scoped_release released;
    result = local_inverse(simulator, y, x0, Vector(), options, domain);
  } catch (const CallbackFailed&) {
    raise_kept(errors, "local inverse " + method);
  }
  py::dict out;
  out["x"] = to_numpy(result.x);
  out["residual"] = result.residual;
  out["iterations"] = result.iterations;
  out["evaluations"] = result.evaluations;
  out["counts"] = counts_dict(result.counts);
  out["converged"] = result.converged;
  return out;
}

py::list rules(RuleKind kind) {
  py::list out;
  for (const RuleInfo& rule : rule_catalogue()) {
    if (rule.kind != kind) continue;
    py::dict d;
    d["id"] = rule.id;
    d["label"] = rule.label;
    d["formula"] = rule.formula;
    d["defaults"] = rule_defaults_text(rule);
    out.append(d);
  }
  return out;
}

}  // namespace

void bind_direct(py::module_& m) {
  py::class_<MinimizeSummary>(m, "MinimizeResult",
                              "What minimize() returned: the final x, the history and the counts.")
      .def_property_readonly("x", [](const MinimizeSummary& s) { return to_numpy(s.x); })
      .def_readonly("loss", &MinimizeSummary::loss)
      .def_readonly("initial_loss", &MinimizeSummary::initial_loss)
      .def_property_readonly("termination",
                             [](const MinimizeSummary& s) { return to_string(s.termination); })
      .def_property_readonly("converged",
                             [](const MinimizeSummary& s) { return converged(s.termination); })
      .def_readonly("message", &MinimizeSummary::message)
      .def_readonly("iterations", &MinimizeSummary::iterations)
      .def_readonly("rejected_steps", &MinimizeSummary::rejected_steps)
      .def_readonly("evaluations", &MinimizeSummary::evaluations)
      .def_property_readonly("counts",
                             [](const MinimizeSummary& s) { return counts_dict(s.counts); })
      .def_readonly("wall_seconds", &MinimizeSummary::wall_seconds)
      .def_readonly("rule", &MinimizeSummary::optimizer)
      .def_property_readonly("params",
                             [](const MinimizeSummary& s) { return to_python(s.params); })
      .def_readonly("at_bounds", &MinimizeSummary::at_bounds)
      .def_property_readonly("loss_history",
                             [](const MinimizeSummary& s) {
                               Vector losses(static_cast<Index>(s.history.size()));
                               for (Index i = 0; i < losses.size(); ++i)
                                 losses(i) = s.history[static_cast<std::size_t>(i)].loss;
                               return to_numpy(losses);
                             })
      .def_property_readonly("x_history",
                             [](const MinimizeSummary& s) {
                               Matrix xs(static_cast<Index>(s.history.size()), s.x.size());
                               for (Index i = 0; i < xs.rows(); ++i)
                                 xs.row(i) = s.history[static_cast<std::size_t>(i)].x.transpose();
                               return to_numpy(xs);
                             })
      .def("brief_report", [](const MinimizeSummary& s) { return brief_report(s); })
      .def("full_report", [](const MinimizeSummary& s) { return full_report(s); })
      .def("__repr__", [](const MinimizeSummary& s) { return "<" + brief_report(s) + ">"; });

  m.def("_minimize", &run_minimize, py::arg("sim"), py::arg("x0"), py::arg("rule"),
        py::arg("target"), py::arg("loss_weight"), py::arg("lower"), py::arg("upper"),
        py::arg("x_scale"), py::arg("max_iterations"), py::arg("loss_tolerance"),
        py::arg("relative_loss_tolerance"), py::arg("gradient_tolerance"),
        py::arg("function_tolerance"), py::arg("parameter_tolerance"),
        py::arg("max_evaluations"), py::arg("max_seconds"), py::arg("callback"),
        py::arg("options"));
  m.def("_local_inverse", &run_local_inverse, py::arg("sim"), py::arg("y"), py::arg("x0"),
        py::arg("method"), py::arg("tolerance"), py::arg("max_iterations"),
        py::arg("relative_tolerance"), py::arg("function_tolerance"), py::arg("rcond"),
        py::arg("lower"), py::arg("upper"));
  m.def("direct_rules", [] { return rules(RuleKind::kDirect); },
        "The direct rules: id, label, formula and defaults of each.");
  m.def("learning_rules", [] { return rules(RuleKind::kLearning); },
        "The learning rules: id, label, formula and defaults of each.");
}

}  // namespace physgrad::python
